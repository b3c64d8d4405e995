// The rays lib/fiv's samplers share (visibility masks, source shadows, the sources' own grid): where a grid
// sample's receiver point lies, which rays can meet the bounding sphere, the inside vote, the source rays.
// Internal to lib/fiv (trace.cpp).
#pragma once

#include "fiv.h"
#include "raycast.h"

#include <array>
#include <cstdint>
#include <vector>

namespace prt::fiv {

// A ray from `origin` along unit `d`, tnear 0, tfar infinity.
RTCRay makeRay(const float origin[3], const float d[3]);

// The occluder's Embree scene and the 26 fixed vote directions (the non-zero points of {-1, 0, 1}^3, slightly
// skewed so none runs along an axis or an edge of an axis-aligned mesh).
struct Tracer {
    const TriMesh& mesh;
    EmbreeScene embree;
    std::vector<std::array<float, 3>> votes;

    explicit Tracer(const TriMesh& m); // EmbreeScene is always robust (lib/raycast)

    // Most of the 26 vote rays first meet a back face: the point is inside. Exact for a closed, consistently wound
    // mesh (every ray then agrees), a majority vote for an open one. Adds the rays cast to `rays`.
    bool inside(const float origin[3], uint64_t& rays) const;
};

// Grid row `row`'s direction d, the vector from its receiver point to the sphere centre (rho R d) and the point
// itself (as float, where every ray of the row starts); returns rho. `radii` = shellRadii(grid).
double receiverPoint(const GridSpec& grid, const BoundingSphere& sphere, const std::vector<double>& radii, size_t row,
                     double d[3], double toCentre[3], float origin[3]);

// Whether a ray from a receiver point at rho R from the sphere centre (toCentre: the vector to it, world units)
// along unit w can meet the bounding sphere: always from inside (rho < 1), else it must point at it and pass
// within R of the centre.
bool canMeetSphere(const double toCentre[3], double rho, double radius, const double w[3]);

// Per-thread buffers of traceSources.
struct SourceScratch {
    std::vector<RTCRay> rays;
    std::vector<uint32_t> texel;
};
// The sources' light the occluder hides from `origin` (a receiver point, toCentre and rho as receiverPoint gives
// them): one ray per source texel that can meet the sphere, as one coherent stream; a hit adds the texel's power
// to `hidden` [3] and power x direction to `fiv` [3][3] (both set, not accumulated). Returns the rays cast.
uint64_t traceSources(const Tracer& tracer, const SmallSources& sources, const float origin[3], const double toCentre[3],
                      double rho, double radius, SourceScratch& scratch, double fiv[9], double hidden[3]);

} // namespace prt::fiv
