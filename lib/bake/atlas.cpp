// Lightmap atlas generation: charts by normal clustering over OpenMesh's face adjacency, planar projection,
// minimal-area rectangles, skyline packing at one texel density with padding.
#include "bake.h"

#include "core.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>
#include <queue>
#include <unordered_map>

namespace prt {

namespace {

using HalfedgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

struct Vec3 {
    double x = 0, y = 0, z = 0;
};
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Vec3 position(const TriMesh& mesh, uint32_t v) {
    return {mesh.positions[3 * size_t(v)], mesh.positions[3 * size_t(v) + 1], mesh.positions[3 * size_t(v) + 2]};
}

// The mesh's triangles as an OpenMesh halfedge mesh, face f being triangle f. Triangles OpenMesh cannot join to
// their neighbours (non-manifold edges or vertices, repeated corners) get vertices of their own: they start
// charts of their own instead of breaking the adjacency of the rest.
HalfedgeMesh halfedgeMesh(const TriMesh& mesh) {
    HalfedgeMesh out;
    std::vector<HalfedgeMesh::VertexHandle> handles(mesh.vertexCount());
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        Vec3 p = position(mesh, uint32_t(v));
        handles[v] = out.add_vertex(HalfedgeMesh::Point(float(p.x), float(p.y), float(p.z)));
    }
    // OpenMesh reports each refused face on its error stream; the refusal is handled here.
    bool errorsWereOn = omerr().is_enabled();
    omerr().disable();
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        HalfedgeMesh::FaceHandle face;
        if (corner[0] != corner[1] && corner[1] != corner[2] && corner[0] != corner[2])
            face = out.add_face(handles[corner[0]], handles[corner[1]], handles[corner[2]]);
        if (!face.is_valid()) {
            HalfedgeMesh::VertexHandle own[3];
            for (int k = 0; k < 3; ++k) own[k] = out.add_vertex(out.point(handles[corner[k]]));
            face = out.add_face(own[0], own[1], own[2]);
        }
    }
    if (errorsWereOn) omerr().enable();
    return out;
}

struct Chart {
    Vec3 axisU, axisV;               // the projection plane, turned to the minimal-area rectangle
    double minU = 0, minV = 0, width = 0, height = 0; // the rectangle in mesh units
    double area = 0;                 // projected area
    std::vector<uint32_t> triangles;
};

// A unit vector orthogonal to unit n.
Vec3 anyOrthogonal(const Vec3& n) {
    double sign = std::copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    return {1.0 + sign * n.x * n.x * a, sign * n.x * n.y * a, -sign * n.x};
}

// 2D convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
std::vector<std::array<double, 2>> convexHull(std::vector<std::array<double, 2>> points) {
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    std::vector<std::array<double, 2>> hull(2 * points.size());
    auto turn = [](const std::array<double, 2>& o, const std::array<double, 2>& a, const std::array<double, 2>& b) {
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    };
    size_t k = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && turn(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
        hull[k++] = points[i];
    }
    for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && turn(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

// The chart's extent along two axes: min and max of the vertices' coordinates.
void extent(const TriMesh& mesh, const Chart& chart, const Vec3& axisU, const Vec3& axisV, double lo[2], double hi[2]) {
    lo[0] = lo[1] = INFINITY, hi[0] = hi[1] = -INFINITY;
    for (uint32_t t : chart.triangles)
        for (int k = 0; k < 3; ++k) {
            Vec3 p = position(mesh, mesh.indices[3 * size_t(t) + k]);
            lo[0] = std::min(lo[0], dot(p, axisU)), hi[0] = std::max(hi[0], dot(p, axisU));
            lo[1] = std::min(lo[1], dot(p, axisV)), hi[1] = std::max(hi[1], dot(p, axisV));
        }
}

// Sets the chart's axes (in the plane of `normal`) to the minimal-area bounding rectangle of its vertices, wider
// than tall, its extent along them and its projected area.
void fitRectangle(const TriMesh& mesh, const Vec3& normal, Chart& chart) {
    Vec3 u = anyOrthogonal(normal), v = cross(normal, u);
    std::vector<std::array<double, 2>> points;
    for (uint32_t t : chart.triangles) {
        std::array<double, 2> corner[3];
        for (int k = 0; k < 3; ++k) {
            Vec3 p = position(mesh, mesh.indices[3 * size_t(t) + k]);
            corner[k] = {dot(p, u), dot(p, v)};
            points.push_back(corner[k]);
        }
        chart.area += 0.5 * std::abs((corner[1][0] - corner[0][0]) * (corner[2][1] - corner[0][1]) -
                                     (corner[1][1] - corner[0][1]) * (corner[2][0] - corner[0][0]));
    }
    std::vector<std::array<double, 2>> hull = convexHull(points);
    // A minimal-area rectangle has a side along a hull edge; the first edge wins ties.
    double bestArea = INFINITY, bestCos = 1.0, bestSin = 0.0;
    for (size_t i = 0; i < hull.size() && hull.size() >= 2; ++i) {
        const auto& a = hull[i];
        const auto& b = hull[(i + 1) % hull.size()];
        double length = std::hypot(b[0] - a[0], b[1] - a[1]);
        double c = (b[0] - a[0]) / length, s = (b[1] - a[1]) / length;
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (const auto& p : hull) {
            double x = c * p[0] + s * p[1], y = -s * p[0] + c * p[1];
            lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
            lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
        }
        double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        if (area < bestArea) bestArea = area, bestCos = c, bestSin = s;
    }
    chart.axisU = {bestCos * u.x + bestSin * v.x, bestCos * u.y + bestSin * v.y, bestCos * u.z + bestSin * v.z};
    chart.axisV = cross(normal, chart.axisU);
    double lo[2], hi[2];
    extent(mesh, chart, chart.axisU, chart.axisV, lo, hi);
    if (hi[1] - lo[1] > hi[0] - lo[0]) {
        // Lay it on its long side, turned by 90 degrees: shelves waste less on charts wider than tall.
        Vec3 turned = {-chart.axisU.x, -chart.axisU.y, -chart.axisU.z};
        chart.axisU = chart.axisV, chart.axisV = turned;
        extent(mesh, chart, chart.axisU, chart.axisV, lo, hi);
    }
    chart.minU = lo[0], chart.minV = lo[1];
    chart.width = hi[0] - lo[0], chart.height = hi[1] - lo[1];
}

// Whether two triangles (corners as 2D points) overlap with positive area: no edge normal of either separates
// them (for convex polygons in the plane an edge normal always does when they only touch or are apart).
bool trianglesOverlap(const std::array<double, 2>* a, const std::array<double, 2>* b, double tolerance) {
    for (const std::array<double, 2>* edges : {a, b})
        for (int e = 0; e < 3; ++e) {
            double nx = edges[(e + 1) % 3][1] - edges[e][1], ny = edges[e][0] - edges[(e + 1) % 3][0];
            double loA = INFINITY, hiA = -INFINITY, loB = INFINITY, hiB = -INFINITY;
            for (int k = 0; k < 3; ++k) {
                double pa = nx * a[k][0] + ny * a[k][1], pb = nx * b[k][0] + ny * b[k][1];
                loA = std::min(loA, pa), hiA = std::max(hiA, pa);
                loB = std::min(loB, pb), hiB = std::max(hiB, pb);
            }
            double slack = tolerance * std::hypot(nx, ny);
            if (hiA <= loB + slack || hiB <= loA + slack) return false;
        }
    return true;
}

// Whether the chart's projection onto the plane of `normal` folds over itself: two of its triangles overlap.
// Candidate pairs come from a uniform grid of about one triangle per cell.
bool foldsOver(const TriMesh& mesh, const std::vector<uint32_t>& triangles, const Vec3& normal) {
    if (triangles.size() < 2) return false;
    Vec3 u = anyOrthogonal(normal), v = cross(normal, u);
    std::vector<std::array<double, 2>> corners(3 * triangles.size());
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; i < triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            Vec3 p = position(mesh, mesh.indices[3 * size_t(triangles[i]) + k]);
            corners[3 * i + k] = {dot(p, u), dot(p, v)};
            for (int a = 0; a < 2; ++a) {
                lo[a] = std::min(lo[a], corners[3 * i + k][a]);
                hi[a] = std::max(hi[a], corners[3 * i + k][a]);
            }
        }
    double extent = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(extent > 0.0)) return false;
    int cells = std::clamp(int(std::sqrt(double(triangles.size()))), 1, 1024);
    double cell = extent / cells * (1 + 1e-9);
    std::vector<std::vector<uint32_t>> grid(size_t(cells) * cells);
    for (size_t i = 0; i < triangles.size(); ++i) {
        const std::array<double, 2>* c = &corners[3 * i];
        int x0 = int((std::min({c[0][0], c[1][0], c[2][0]}) - lo[0]) / cell);
        int x1 = int((std::max({c[0][0], c[1][0], c[2][0]}) - lo[0]) / cell);
        int y0 = int((std::min({c[0][1], c[1][1], c[2][1]}) - lo[1]) / cell);
        int y1 = int((std::max({c[0][1], c[1][1], c[2][1]}) - lo[1]) / cell);
        for (int y = y0; y <= std::min(y1, cells - 1); ++y)
            for (int x = x0; x <= std::min(x1, cells - 1); ++x) grid[size_t(y) * cells + x].push_back(uint32_t(i));
    }
    double tolerance = 1e-9 * extent;
    for (const std::vector<uint32_t>& bin : grid)
        for (size_t i = 0; i < bin.size(); ++i)
            for (size_t j = i + 1; j < bin.size(); ++j)
                if (trianglesOverlap(&corners[3 * size_t(bin[i])], &corners[3 * size_t(bin[j])], tolerance))
                    return true;
    return false;
}

// Charts by normal clustering over face adjacency. Every face's normal has positive dot product with its chart's
// seed normal, so no triangle flips in the chart's projection; a chart whose projection still folds over itself
// (a surface curling round) is cut up again with half the cone, down to single faces.
class ChartGrower {
public:
    ChartGrower(const TriMesh& mesh, const HalfedgeMesh& halfedges) : mesh_(mesh), halfedges_(halfedges) {
        size_t faceCount = mesh.triangleCount();
        faceNormal_.resize(faceCount);
        for (size_t t = 0; t < faceCount; ++t) {
            const uint32_t* c = &mesh.indices[3 * t];
            Vec3 p0 = position(mesh, c[0]), p1 = position(mesh, c[1]), p2 = position(mesh, c[2]);
            Vec3 n = cross({p1.x - p0.x, p1.y - p0.y, p1.z - p0.z}, {p2.x - p0.x, p2.y - p0.y, p2.z - p0.z});
            double length = std::sqrt(dot(n, n));
            faceNormal_[t] = length > 0.0 ? Vec3{n.x / length, n.y / length, n.z / length} : Vec3{};
        }
        chartOf_.assign(faceCount, kFree);
        region_.assign(faceCount, 0);
    }

    // Charts of every face, each grown within `coneAngle` degrees of its seed's normal where that does not fold.
    std::vector<Chart> grow(double coneAngle, std::vector<uint32_t>& chartOf) {
        std::vector<uint32_t> all(mesh_.triangleCount());
        for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
        partition(all, 0, coneAngle);
        chartOf = chartOf_;
        return std::move(charts_);
    }

private:
    static constexpr uint32_t kFree = UINT32_MAX;

    // Splits the free faces of `faces` (all in region `region`) into charts.
    void partition(const std::vector<uint32_t>& faces, uint32_t region, double coneAngle) {
        const double minCos = std::cos(coneAngle * std::numbers::pi / 180.0);
        for (uint32_t seed : faces) {
            if (chartOf_[seed] != kFree) continue;
            Vec3 normal = faceNormal_[seed];
            if (dot(normal, normal) == 0.0) normal = {0.0, 1.0, 0.0}; // zero area: any plane projects it to nothing
            uint32_t id = uint32_t(charts_.size());
            Chart chart;
            // Candidates by (1 - cos) to the seed normal, then face index: a fixed order.
            using Candidate = std::pair<double, uint32_t>;
            std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue;
            queue.push({0.0, seed});
            while (!queue.empty()) {
                uint32_t face = queue.top().second;
                queue.pop();
                if (chartOf_[face] != kFree) continue;
                chartOf_[face] = id;
                chart.triangles.push_back(face);
                if (coneAngle < kMinConeAngle) continue; // single faces
                for (auto neighbour : halfedges_.ff_range(HalfedgeMesh::FaceHandle(int(face)))) {
                    uint32_t f = uint32_t(neighbour.idx());
                    if (chartOf_[f] != kFree || region_[f] != region) continue;
                    double c = dot(faceNormal_[f], normal);
                    bool degenerate = dot(faceNormal_[f], faceNormal_[f]) == 0.0;
                    if (c >= minCos || degenerate) queue.push({degenerate ? 1.0 : 1.0 - c, f});
                }
            }
            std::sort(chart.triangles.begin(), chart.triangles.end());
            if (coneAngle >= kMinConeAngle && foldsOver(mesh_, chart.triangles, normal)) {
                uint32_t inner = ++regions_;
                for (uint32_t f : chart.triangles) chartOf_[f] = kFree, region_[f] = inner;
                partition(chart.triangles, inner, 0.5 * coneAngle);
                continue;
            }
            fitRectangle(mesh_, normal, chart);
            charts_.push_back(std::move(chart));
        }
    }

    static constexpr double kMinConeAngle = 1.0;
    const TriMesh& mesh_;
    const HalfedgeMesh& halfedges_;
    std::vector<Vec3> faceNormal_;
    std::vector<uint32_t> chartOf_, region_;
    uint32_t regions_ = 0;
    std::vector<Chart> charts_;
};

// Chart placements in texels for `texelsPerUnit`, by the skyline bottom-left rule: charts in order of height,
// each reserving its covered texels plus `padding`, placed where its top ends lowest (then leftmost).
// Returns false when they do not fit in width x height.
bool skylinePack(const std::vector<Chart>& charts, const std::vector<uint32_t>& byHeight, double texelsPerUnit,
                 int width, int height, int padding, std::vector<std::array<long, 2>>& origin) {
    origin.assign(charts.size(), {0, 0});
    struct Segment {
        long x, width, y;
    };
    std::vector<Segment> skyline = {{0, width, 0}};
    for (uint32_t c : byHeight) {
        long w = long(std::ceil(charts[c].width * texelsPerUnit)) + padding;
        long h = long(std::ceil(charts[c].height * texelsPerUnit)) + padding;
        if (w > width) return false;
        long bestY = LONG_MAX;
        size_t best = 0;
        for (size_t i = 0; i < skyline.size() && skyline[i].x + w <= width; ++i) {
            long y = 0;
            for (size_t j = i; j < skyline.size() && skyline[j].x < skyline[i].x + w; ++j)
                y = std::max(y, skyline[j].y);
            if (y < bestY) bestY = y, best = i;
        }
        if (bestY == LONG_MAX || bestY + h > height) return false;
        long x = skyline[best].x;
        origin[c] = {x + padding / 2, bestY + padding / 2};
        // The new segment replaces what it covers; a segment it covers partly keeps its remainder.
        std::vector<Segment> next(skyline.begin(), skyline.begin() + long(best));
        next.push_back({x, w, bestY + h});
        for (size_t j = best; j < skyline.size(); ++j) {
            long end = skyline[j].x + skyline[j].width;
            if (end <= x + w) continue;
            long start = std::max(skyline[j].x, x + w);
            next.push_back({start, end - start, skyline[j].y});
        }
        skyline.clear();
        for (const Segment& segment : next)
            if (!skyline.empty() && skyline.back().y == segment.y)
                skyline.back().width += segment.width;
            else
                skyline.push_back(segment);
    }
    return true;
}

// The largest texel density (to 0.1 %) at which the charts pack, and their origins there.
double packCharts(const std::vector<Chart>& charts, const AtlasOptions& options,
                  std::vector<std::array<long, 2>>& origin) {
    std::vector<uint32_t> byHeight(charts.size());
    for (uint32_t c = 0; c < charts.size(); ++c) byHeight[c] = c;
    std::stable_sort(byHeight.begin(), byHeight.end(),
                     [&](uint32_t a, uint32_t b) { return charts[a].height > charts[b].height; });
    double area = 0.0;
    for (const Chart& chart : charts) area += chart.area;
    // Start from a density that fills the atlas completely; packing can only do worse.
    double hi = std::sqrt(double(options.width) * options.height / std::max(area, 1e-30));
    double lo = hi;
    for (int attempt = 0; !skylinePack(charts, byHeight, lo, options.width, options.height, options.padding, origin);
         ++attempt) {
        if (attempt == 200)
            throw Error("", "atlas",
                        std::to_string(charts.size()) + " charts do not fit in " + std::to_string(options.width) +
                            "x" + std::to_string(options.height) + " texels with " +
                            std::to_string(options.padding) + " texels of padding; raise --resolution",
                        kExitInput);
        hi = lo;
        lo *= 0.8;
    }
    while (hi - lo > 1e-3 * lo) {
        double mid = 0.5 * (lo + hi);
        if (skylinePack(charts, byHeight, mid, options.width, options.height, options.padding, origin))
            lo = mid;
        else
            hi = mid;
    }
    skylinePack(charts, byHeight, lo, options.width, options.height, options.padding, origin);
    return lo;
}

GeneratedAtlas layOut(const TriMesh& mesh, const std::vector<Chart>& charts, const std::vector<uint32_t>& chartOf,
                      const AtlasOptions& options) {
    std::vector<std::array<long, 2>> origin;
    double scale = packCharts(charts, options, origin);
    GeneratedAtlas atlas;
    atlas.charts = charts.size();
    atlas.texelsPerUnit = scale;
    atlas.chart = chartOf;
    TriMesh& out = atlas.mesh;
    out.indices.resize(mesh.indices.size());
    std::unordered_map<uint64_t, uint32_t> copyOf; // (input vertex, chart) -> output vertex
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const Chart& chart = charts[chartOf[t]];
        for (int k = 0; k < 3; ++k) {
            uint32_t v = mesh.indices[3 * t + k];
            uint64_t key = uint64_t(chartOf[t]) << 32 | v;
            auto [slot, added] = copyOf.try_emplace(key, uint32_t(atlas.sourceVertex.size()));
            out.indices[3 * t + k] = slot->second;
            if (!added) continue;
            atlas.sourceVertex.push_back(v);
            Vec3 p = position(mesh, v);
            double x = origin[chartOf[t]][0] + (dot(p, chart.axisU) - chart.minU) * scale;
            double y = origin[chartOf[t]][1] + (dot(p, chart.axisV) - chart.minV) * scale;
            out.texcoords.push_back(float(std::clamp(x / options.width, 0.0, 1.0)));
            out.texcoords.push_back(float(std::clamp(y / options.height, 0.0, 1.0)));
        }
    }
    for (uint32_t v : atlas.sourceVertex) {
        for (int a = 0; a < 3; ++a) out.positions.push_back(mesh.positions[3 * size_t(v) + a]);
        if (!mesh.normals.empty())
            for (int a = 0; a < 3; ++a) out.normals.push_back(mesh.normals[3 * size_t(v) + a]);
        if (!mesh.albedo.empty())
            for (int a = 0; a < 3; ++a) out.albedo.push_back(mesh.albedo[3 * size_t(v) + a]);
    }
    return atlas;
}

} // namespace

GeneratedAtlas generateAtlas(const TriMesh& mesh, const AtlasOptions& options) {
    if (options.width < 8 || options.height < 8 || options.width > kMaxBakeResolution ||
        options.height > kMaxBakeResolution)
        throw Error("", "atlas", "size outside 8.." + std::to_string(kMaxBakeResolution), kExitUsage);
    if (options.padding < 2) throw Error("", "--padding", "must be at least 2 texels", kExitUsage);
    if (!(options.chartAngle > 0.0 && options.chartAngle < 90.0))
        throw Error("", "atlas", "the chart cone must lie in (0, 90) degrees", kExitUsage);
    if (mesh.triangleCount() == 0) throw Error("", "mesh", "has no triangles");
    HalfedgeMesh halfedges = halfedgeMesh(mesh);
    std::vector<uint32_t> chartOf;
    std::vector<Chart> charts = ChartGrower(mesh, halfedges).grow(options.chartAngle, chartOf);
    GeneratedAtlas atlas = layOut(mesh, charts, chartOf, options);
    RasterOptions raster;
    raster.width = options.width;
    raster.height = options.height;
    raster.allowOverlap = true;
    size_t overlaps = rasteriseAtlas(atlas.mesh, raster, "generated atlas").overlappingTexels;
    if (overlaps > 0)
        throw Error("", "generated atlas", std::to_string(overlaps) + " texels overlap (a bug)", kExitFailure);
    return atlas;
}

} // namespace prt
