// The rays lib/fiv's samplers share (fiv_internal.h): receiver points, the sphere test, the inside vote, the
// source rays.
#include "fiv_internal.h"

#include "core.h"

#include <cmath>
#include <limits>

namespace prt::fiv {

namespace {

std::vector<std::array<float, 3>> voteDirections() {
    std::vector<std::array<float, 3>> out;
    for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
            for (int z = -1; z <= 1; ++z) {
                if (!x && !y && !z) continue;
                double d[3] = {x + 0.0123, y + 0.0217, z - 0.0171};
                double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                out.push_back({float(d[0] / n), float(d[1] / n), float(d[2] / n)});
            }
    return out;
}

} // namespace

RTCRay makeRay(const float origin[3], const float d[3]) {
    RTCRay ray{};
    ray.org_x = origin[0], ray.org_y = origin[1], ray.org_z = origin[2];
    ray.dir_x = d[0], ray.dir_y = d[1], ray.dir_z = d[2];
    ray.tnear = 0.0f;
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.mask = ~0u;
    return ray;
}

Tracer::Tracer(const TriMesh& m) : mesh(m), embree(m), votes(voteDirections()) {}

bool Tracer::inside(const float origin[3], uint64_t& rays) const {
    int backFaces = 0;
    for (const auto& d : votes) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit hit{};
        hit.ray = makeRay(origin, d.data());
        hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(embree.scene, &context, &hit);
        ++rays;
        if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const uint32_t* tri = &mesh.indices[3 * size_t(hit.hit.primID)];
        const float* p0 = &mesh.positions[3 * size_t(tri[0])];
        const float* p1 = &mesh.positions[3 * size_t(tri[1])];
        const float* p2 = &mesh.positions[3 * size_t(tri[2])];
        float e1[3], e2[3];
        for (int c = 0; c < 3; ++c) e1[c] = p1[c] - p0[c], e2[c] = p2[c] - p0[c];
        float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0f) ++backFaces;
    }
    return 2 * backFaces > int(votes.size());
}

double receiverPoint(const GridSpec& grid, const BoundingSphere& sphere, const std::vector<double>& radii, size_t row,
                     double d[3], double toCentre[3], float origin[3]) {
    int i = int(row % size_t(grid.azimuth)), j = int(row / size_t(grid.azimuth) % size_t(grid.polar));
    int k = int(row / (size_t(grid.azimuth) * grid.polar));
    double rho = radii[size_t(k)], radius = sphere.radius;
    gridDirection(grid, i, j, d);
    for (int c = 0; c < 3; ++c) {
        toCentre[c] = rho * radius * d[c];
        origin[c] = float(sphere.centre[size_t(c)] - toCentre[c]);
    }
    return rho;
}

bool canMeetSphere(const double toCentre[3], double rho, double radius, const double w[3]) {
    if (rho < 1.0) return true;
    double along = toCentre[0] * w[0] + toCentre[1] * w[1] + toCentre[2] * w[2];
    return along > 0.0 && !(along * along < rho * rho * radius * radius - radius * radius);
}

uint64_t traceSources(const Tracer& tracer, const SmallSources& sources, const float origin[3], const double toCentre[3],
                      double rho, double radius, SourceScratch& scratch, double fiv[9], double hidden[3]) {
    std::fill(fiv, fiv + 9, 0.0);
    std::fill(hidden, hidden + 3, 0.0);
    const size_t texels = sources.direction.size() / 3;
    scratch.rays.clear();
    scratch.texel.clear();
    for (size_t t = 0; t < texels; ++t) {
        const double* w = &sources.direction[3 * t];
        if (!canMeetSphere(toCentre, rho, radius, w)) continue;
        float wf[3] = {float(w[0]), float(w[1]), float(w[2])};
        scratch.rays.push_back(makeRay(origin, wf));
        scratch.texel.push_back(uint32_t(t));
    }
    if (scratch.rays.empty()) return 0;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded1M(tracer.embree.scene, &context, scratch.rays.data(), unsigned(scratch.rays.size()), sizeof(RTCRay));
    for (size_t r = 0; r < scratch.rays.size(); ++r) {
        if (!(scratch.rays[r].tfar < 0.0f)) continue;
        const size_t t = scratch.texel[r];
        for (int c = 0; c < 3; ++c) {
            hidden[c] += sources.power[3 * t + size_t(c)];
            for (int a = 0; a < 3; ++a) fiv[3 * c + a] += sources.power[3 * t + size_t(c)] * sources.direction[3 * t + size_t(a)];
        }
    }
    return scratch.rays.size();
}

} // namespace prt::fiv
