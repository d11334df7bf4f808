#include "render/ShaderContract.h"

#include "light/AtmosphereTables.h"

#include "render/ShaderProgram.h"

namespace terrain::contract {

std::vector<std::string> shaderContractDefines()
{
    auto define = [](const char* name, auto value) { return std::string(name) + " " + std::to_string(value); };
    return {
        define("GRID_LOCATION", kGridLocation),
        define("SKIRT_LOCATION", kSkirtLocation),
        define("PATCH_LOCATION", kPatchLocation),
        define("NODE0_LOCATION", kNodeLocation),
        define("NODE1_LOCATION", kNodeLocation + 1),
        define("NODE2_LOCATION", kNodeLocation + 2),
        define("LAYER_ORIGIN_LOCATION", kLayerOriginLocation),
        define("BLOCK_LEVEL_MASK", kBlockLevelMask),
        define("BLOCK_SNAP_SHIFT", kBlockSnapShift),
        define("BLOCK_SNAP_BITS", kBlockSnapBits),
        define("BLOCK_CULLED_BIT", kBlockCulledBit),
        define("AERIAL_TABLE_AZIMUTHS", kAerialTableAzimuths),
        define("AERIAL_TABLE_ELEVATIONS", kAerialTableElevations),
        define("AERIAL_TABLE_DISTANCES", kAerialTableDistances),
        define("AERIAL_TABLE_SAMPLES", kAerialSamples),
        define("SKY_TABLE_AZIMUTHS", kSkyTableAzimuths),
        define("SKY_TABLE_ELEVATIONS", kSkyTableElevations),
        define("SKY_TABLE_SAMPLES", kSkySamples),
        define("MULTIPLE_SCATTERING_ALTITUDES", kMultipleScatteringAltitudes),
        define("GROUND_ALBEDO", kGroundAlbedo),
    };
}

void bindSamplerUnits(const ShaderProgram& program, std::span<const SamplerUnit> table)
{
    program.use();
    for (const SamplerUnit& sampler : table) {
        if (const GLint location = program.uniform(sampler.uniform); location >= 0) {
            glUniform1i(location, sampler.unit);
        }
    }
}

}  // namespace terrain::contract
