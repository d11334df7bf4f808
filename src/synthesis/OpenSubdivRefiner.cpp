// Bilinear and Catmull-Clark subdivision of a node window through OpenSubdiv's Far API (uniform refinement,
// level 1), the alternatives to Kobbelt's rule for `detail_subdivision_scheme` (paper 3.3.2).
// Built with -ffp-contract=off (src/synthesis/CMakeLists.txt) like KobbeltSubdivider.cpp: the primvar
// accumulation below is instantiated here.
#include "synthesis/OpenSubdivRefiner.h"

#include "core/Check.h"

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

namespace terrain {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

struct OpenSubdivRefiner::Topology {
    std::unique_ptr<Far::TopologyRefiner> refiner;
};

namespace {

/// One height as an OpenSubdiv primvar (the Clear / AddWithWeight interface PrimvarRefiner templates on).
struct HeightPrimvar {
    double h;
    void Clear() { h = 0.0; }
    void AddWithWeight(const HeightPrimvar& source, double weight) { h += weight * source.h; }
};

}  // namespace

OpenSubdivRefiner::OpenSubdivRefiner(int chunkSize, OpenSubdivScheme scheme)
    : mChunkSize(chunkSize), mScheme(scheme), mPatchSize((chunkSize + 9) / 2)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    const int m = mPatchSize;
    auto vertex = [m](int x, int y) { return y * m + x; };

    // The M x M quad grid, faces counter-clockwise seen from above (x east, y north).
    std::vector<int> vertsPerFace(static_cast<std::size_t>(m - 1) * (m - 1), 4);
    std::vector<int> faceVerts;
    faceVerts.reserve(vertsPerFace.size() * 4);
    for (int y = 0; y + 1 < m; ++y) {
        for (int x = 0; x + 1 < m; ++x) {
            faceVerts.insert(faceVerts.end(), {vertex(x, y), vertex(x + 1, y), vertex(x + 1, y + 1), vertex(x, y + 1)});
        }
    }
    Far::TopologyDescriptor descriptor;
    descriptor.numVertices = m * m;
    descriptor.numFaces = static_cast<int>(vertsPerFace.size());
    descriptor.numVertsPerFace = vertsPerFace.data();
    descriptor.vertIndicesPerFace = faceVerts.data();

    Sdc::Options options;
    options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);  // never reaches a child sample
    using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
    Sdc::SchemeType type = scheme == OpenSubdivScheme::Bilinear ? Sdc::SCHEME_BILINEAR : Sdc::SCHEME_CATMARK;
    auto topology = std::make_unique<Topology>();
    topology->refiner.reset(Factory::Create(descriptor, Factory::Options(type, options)));
    TERRAIN_ASSERT(topology->refiner != nullptr);
    topology->refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(1));

    const Far::TopologyLevel& coarse = topology->refiner->GetLevel(0);
    mRefinedCount = topology->refiner->GetLevel(1).GetNumVertices();
    // Child window index c sits at refined patch index r = c + 2 (the patch starts one parent sample before
    // the child's u = -2): even r is a parent vertex, odd r an edge midpoint, odd in both a face centre.
    const int size = windowSize(chunkSize);
    TERRAIN_ASSERT(size + 3 <= 2 * (m - 1));  // the last child sample's 1-ring is inside the patch
    mChildToRefined.resize(static_cast<std::size_t>(size) * size);
    for (int cy = 0; cy < size; ++cy) {
        for (int cx = 0; cx < size; ++cx) {
            int rx = cx + 2;
            int ry = cy + 2;
            int x = rx / 2;
            int y = ry / 2;
            Far::Index child = 0;
            if (rx % 2 == 0 && ry % 2 == 0) {
                child = coarse.GetVertexChildVertex(vertex(x, y));
            } else if (ry % 2 == 0) {
                child = coarse.GetEdgeChildVertex(coarse.FindEdge(vertex(x, y), vertex(x + 1, y)));
            } else if (rx % 2 == 0) {
                child = coarse.GetEdgeChildVertex(coarse.FindEdge(vertex(x, y), vertex(x, y + 1)));
            } else {
                child = coarse.GetFaceChildVertex(y * (m - 1) + x);
            }
            TERRAIN_ASSERT(child >= 0 && child < mRefinedCount);
            mChildToRefined[static_cast<std::size_t>(cy) * size + cx] = child;
        }
    }
    mTopology = std::move(topology);
}

OpenSubdivRefiner::~OpenSubdivRefiner() = default;

void OpenSubdivRefiner::subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const
{
    TERRAIN_EXPECTS(quadrant >= 0 && quadrant <= 3, "quadrant must be 0..3");
    const int size = windowSize(mChunkSize);
    const auto count = static_cast<std::size_t>(size) * size;
    TERRAIN_EXPECTS(parent.size() == count && child.size() == count, "windows must hold W*W samples, W = N + 4");

    const int m = mPatchSize;
    const int half = (mChunkSize - 1) / 2;
    const int x0 = (quadrant & 1) * half;  // parent window index of the patch's first sample
    const int y0 = (quadrant >> 1) * half;
    std::vector<HeightPrimvar> buffer(static_cast<std::size_t>(m) * m + static_cast<std::size_t>(mRefinedCount));
    for (int y = 0; y < m; ++y) {
        for (int x = 0; x < m; ++x) {
            buffer[static_cast<std::size_t>(y) * m + x].h = parent[static_cast<std::size_t>(y0 + y) * size + x0 + x];
        }
    }
    HeightPrimvar* source = buffer.data();  // named: Interpolate binds its arguments by reference
    HeightPrimvar* refined = source + static_cast<std::ptrdiff_t>(m) * m;
    Far::PrimvarRefinerReal<double>(*mTopology->refiner).Interpolate(1, source, refined);
    for (std::size_t i = 0; i < count; ++i) {
        child[i] = static_cast<float>(refined[mChildToRefined[i]].h);
    }
}

}  // namespace terrain
