// What every frame of the terrain renderers (quadtree nodes, clipmap rings) sets up alike: the viewport, the
// clear, the sky, depth testing, and the uniforms their programs take from the camera, the scene's light and
// the map (shaders/light.glsl, the valid rectangle).
#pragma once

#include "core/Camera.h"
#include "quadtree/MapFormat.h"
#include "render/ShaderProgram.h"
#include "render/Sky.h"

#include <glm/vec4.hpp>

namespace terrain {

/// When the sky is drawn (SceneStyle::drawSky). After the terrain, only the pixels the terrain leaves at the
/// depth's clear value run the sky's program; before it, every pixel does. A terrain whose discarded fragments
/// write depth (early fragment tests with discards) needs the sky first, or those pixels keep the clear colour.
enum class SkyOrder { AfterTerrain, BeforeTerrain };

/// Brings the sky's air tables up to the frame (Sky::prepare), sets the viewport to the camera's, clears colour
/// and depth, draws the sky when `order` is BeforeTerrain, then turns depth testing on (less) and sets the polygon
/// mode (SceneStyle::wireframe). Face culling is the caller's.
void beginSceneFrame(const Camera& camera, const SceneStyle& style, Sky& sky, SkyOrder order);

/// After the terrain: the polygon mode back to fill and, when `order` is AfterTerrain, the sky.
void endSceneFrame(const Camera& camera, const SceneStyle& style, const Sky& sky, SkyOrder order);

/// The map's input samples (prep's padding left out) as world metres: x0, y0, x1, y1 of the first and last
/// samples.
glm::dvec4 validRectangle(const MapHeader& header);

/// Sets the atmosphere's uniforms (shaders/atmosphere.glsl) on `program`, which must be in use: the air's constants
/// and the exposure of `style`, the camera's altitude (its z) and the aerial table's range (aerialTableRange).
/// Programs without the atmosphere ignore them.
void setAtmosphereUniforms(const ShaderProgram& program, const Camera& camera, const SceneStyle& style);
/// psi_ms and the sky's irradiance (light/Atmosphere.h) as `program`'s uMultipleScattering, uSkyIrradiance and
/// uMultipleScatteringTop (atmosphere.glsl's in-scattering sums and the ground's skylight; the program is in use).
void setMultipleScatteringUniforms(const ShaderProgram& program, const MultipleScattering& multiple);

/// Sets the uniforms every terrain program takes from the frame on `program` (which it uses): uViewProjection,
/// uHeightBase (the map's height offset below the camera), the sun, ambient and haze of `style`, uWireframe,
/// the atmosphere's (setAtmosphereUniforms) and uValidRect (validRectangle, camera-relative, grown by a thousandth of a
/// sample so that fragments on the last sample stay).
void setSceneUniforms(const ShaderProgram& program, const Camera& camera, const SceneStyle& style,
                      const MapHeader& header);

}  // namespace terrain
