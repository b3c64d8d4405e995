// FIV shading at run time: DifMap lookups, trilinear FIV fetches and the seed's cases, partial and overlap
// corrections (runtime.h, docs/fiv.md). std, lib/bundle and lib/core only: an engine can port it to a shader.
#include "runtime.h"

#include "core.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt {

namespace {

constexpr double kPi = std::numbers::pi;

float dot3(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Angle between unit vectors, accurate for tiny angles (acos of a dot product is not): 0 for equal vectors.
double angleBetween(const float* a, const float* b) {
    double d[3] = {double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]};
    double chord = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return 2.0 * std::asin(std::min(1.0, 0.5 * chord));
}

std::string shapeText(const std::vector<uint64_t>& shape) {
    std::string text;
    for (uint64_t axis : shape) text += (text.empty() ? "" : ",") + std::to_string(axis);
    return "[" + text + "]";
}

// A number param (JSON number, not a string or bool), as a float that is finite and within kFivMaxCoordinate.
float coordinateParam(const nlohmann::json& value, const std::string& source, const std::string& place) {
    if (!value.is_number())
        throw Error(source, place, "is " + std::string(value.type_name()) + ", not a number");
    double x = value.get<double>();
    float f = float(x);
    if (!std::isfinite(x) || !std::isfinite(f) || std::abs(x) > kFivMaxCoordinate)
        throw Error(source, place, "is not a finite number within +-" + std::to_string(int64_t(kFivMaxCoordinate)));
    return f;
}

int intParam(const Layer& layer, const char* key, const std::string& source, int lo, int hi) {
    const nlohmann::json& p = layer.params;
    if (!p.contains(key) || !p.at(key).is_number_integer())
        throw Error(source, layer.name, std::string("params.") + key + " is missing or not an integer");
    long long v = p.at(key).get<long long>();
    if (v < lo || v > hi)
        throw Error(source, layer.name, std::string("params.") + key + " = " + std::to_string(v) + " is outside " +
                                            std::to_string(lo) + ".." + std::to_string(hi));
    return int(v);
}

std::string stringParam(const Layer& layer, const char* key) {
    // Absent or not a string: "", which matches no environment hash.
    const nlohmann::json& p = layer.params;
    return p.contains(key) && p.at(key).is_string() ? p.at(key).get<std::string>() : std::string();
}

// Weighted sum of grid rows into fiv/power; rows with valid == 0 are skipped. Returns the weight used.
struct Corner {
    size_t row;
    float weight;
};

float gather(const FivOccluder& o, const Corner* corners, int count, float fiv[9], float power[3]) {
    float total = 0.0f;
    std::fill(fiv, fiv + 9, 0.0f);
    std::fill(power, power + 3, 0.0f);
    for (int c = 0; c < count; ++c) {
        if (corners[c].weight <= 0.0f || !o.valid[corners[c].row]) continue;
        float w = corners[c].weight;
        const float* f = &o.fiv[9 * corners[c].row];
        const float* p = &o.power[3 * corners[c].row];
        for (int e = 0; e < 9; ++e) fiv[e] += w * f[e];
        for (int e = 0; e < 3; ++e) power[e] += w * p[e];
        total += w;
    }
    return total;
}

// The source grid's sharpened fraction g = clamp(0.5 + K (f - 0.5), 0, 1).
float sharpened(float f, float k) { return std::clamp(0.5f + k * (f - 0.5f), 0.0f, 1.0f); }

// Irradiance the occluder hides from a receiver whose tangent plane lies `d` from the sphere centre, per channel.
void occludedIrradiance(const float n[3], const float fiv[9], const float power[3], float d, float radius,
                        FivPartial partial, float out[3]) {
    for (int c = 0; c < 3; ++c) {
        const float* f = &fiv[3 * c];
        float raw = dot3(n, f);
        if (d >= radius || partial == FivPartial::None) {
            out[c] = std::max(0.0f, raw);
        } else if (partial == FivPartial::Literal) {
            out[c] = std::max(0.0f, (d + radius) / (2.0f * radius) * raw);
        } else {
            double length = std::sqrt(double(dot3(f, f)));
            if (!(length > 0.0) || !(power[c] > 0.0f)) {
                out[c] = 0.0f;
                continue;
            }
            // A uniform cap with the same power P and vector |F| has mean cosine |F| / P = (1 + cos sigma) / 2.
            double cosSigma = std::clamp(2.0 * length / power[c] - 1.0, 0.0, 1.0 - 1e-7);
            double sin2 = 1.0 - cosSigma * cosSigma;
            double radiance = power[c] / (2.0 * kPi * (1.0 - cosSigma));
            out[c] = float(std::max(0.0, radiance * clippedCapIrradiance(raw / length, sin2)));
        }
    }
}

} // namespace

double clippedCapIrradiance(double cosTheta, double sinSigmaSquared) {
    return sh::capCosineIntegral(cosTheta, sinSigmaSquared);
}

double discOverlap(double r1, double r2, double s) {
    if (s >= r1 + r2) return 0.0;
    if (s <= std::abs(r1 - r2)) return kPi * std::pow(std::min(r1, r2), 2);
    double a = std::clamp((s * s + r1 * r1 - r2 * r2) / (2.0 * s * r1), -1.0, 1.0);
    double b = std::clamp((s * s + r2 * r2 - r1 * r1) / (2.0 * s * r2), -1.0, 1.0);
    double k = (-s + r1 + r2) * (s + r1 - r2) * (s - r1 + r2) * (s + r1 + r2);
    return r1 * r1 * std::acos(a) + r2 * r2 * std::acos(b) - 0.5 * std::sqrt(std::max(0.0, k));
}

const Layer& fivLayer(const Bundle& bundle, const std::string& name, uint32_t object, const char* semantic,
                      FivStorage storage, const std::vector<uint64_t>& shape, const std::string& source) {
    const std::string place = objectLayerName(name, object);
    const Layer* layer = findObjectLayer(bundle, name, object);
    if (!layer) throw Error(source, place, "layer is missing (not a FIV bundle from `prt fiv`)");
    if (semantic && layer->semantic != semantic)
        throw Error(source, place, "semantic is \"" + layer->semantic + "\", not " + semantic);
    const std::string& type = layer->componentType;
    bool typed = storage == FivStorage::Float ? type == "float16" || type == "float32"
                 : storage == FivStorage::Uint8 ? type == "uint8" : type == "uint32";
    const char* want = storage == FivStorage::Float ? "float16 or float32" : storage == FivStorage::Uint8 ? "uint8" : "uint32";
    if (shape.empty() ? layer->shape.size() != 1 : layer->shape != shape)
        throw Error(source, place, "shape " + shapeText(layer->shape) + " disagrees with the grid header, which needs " +
                                       (shape.empty() ? std::string("one axis") : shapeText(shape)));
    uint64_t count = 1;
    for (uint64_t axis : layer->shape) count = axis && count > UINT64_MAX / axis ? UINT64_MAX : count * axis;
    // An empty layer (a shard's mask bits when all its rows are inside) has no storage to misread, and a glTF
    // file keeps no component type for it.
    if (count == 0) return *layer;
    if (!typed) throw Error(source, place, "component type is " + type + ", not " + want);
    size_t held = storage == FivStorage::Float ? layer->data.size() : layer->integers.size();
    if (held != count)
        throw Error(source, place, "holds " + std::to_string(held) + " values, its shape " + shapeText(layer->shape) +
                                       " needs " + std::to_string(count));
    if (storage == FivStorage::Float)
        for (float v : layer->data)
            if (!std::isfinite(v)) throw Error(source, place, "holds a non-finite value");
    return *layer;
}

void checkFivPoints(const std::vector<float>& positions, const std::string& source) {
    for (size_t i = 0; i < positions.size(); ++i)
        if (!std::isfinite(positions[i]) || std::abs(double(positions[i])) > kFivMaxCoordinate)
            throw Error(source, "vertex " + std::to_string(i / 3), "position is not finite or lies beyond +-" +
                                                                     std::to_string(int64_t(kFivMaxCoordinate)));
}

namespace {

// Layers fiv_source_grid / fiv_source_valid of `object`, checked through fivLayer and against the main grid `o`.
FivSourceGrid sourceGrid(const Bundle& bundle, const std::string& source, uint32_t object, const FivOccluder& o) {
    const Layer* header = findObjectLayer(bundle, "fiv_source_grid", object);
    FivSourceGrid g;
    g.azimuth = intParam(*header, "azimuth", source, 3, 4096);
    g.polar = intParam(*header, "polar", source, 2, 2049);
    g.shells = intParam(*header, "shells", source, 1, 1024);
    uint64_t rows = uint64_t(g.azimuth) * g.polar * g.shells;
    if (rows > (uint64_t(1) << 26))
        throw Error(source, objectLayerName("fiv_source_grid", object), "holds more than 2^26 samples");
    const Layer& fraction = fivLayer(bundle, "fiv_source_grid", object, "fiv_source_hidden_fraction", FivStorage::Float,
                                     {rows}, source);
    const Layer& valid = fivLayer(bundle, "fiv_source_valid", object, "fiv_valid", FivStorage::Uint8, {rows}, source);
    const std::string name = objectLayerName("fiv_source_grid", object);
    for (float f : fraction.data)
        if (!(f >= 0.0f && f <= 1.0f)) throw Error(source, name, "holds a fraction outside 0..1");
    for (uint32_t v : valid.integers)
        if (v > 1) throw Error(source, objectLayerName("fiv_source_valid", object), "holds a value other than 0 and 1");
    const std::string place = name + ", params.";
    const nlohmann::json& p = fraction.params;
    // The same occluder: its bounding sphere, as the main grid's header gives it.
    if (!p.contains("radius") || coordinateParam(p.at("radius"), source, place + "radius") != o.radius)
        throw Error(source, place + "radius", "is missing or differs from the main grid's (not the same occluder)");
    if (!p.contains("centre") || !p.at("centre").is_array() || p.at("centre").size() != 3)
        throw Error(source, place + "centre", "is not an array of 3 numbers");
    for (int c = 0; c < 3; ++c)
        if (coordinateParam(p.at("centre")[size_t(c)], source, place + "centre[" + std::to_string(c) + "]") != o.centre[c])
            throw Error(source, place + "centre", "differs from the main grid's (not the same occluder)");
    if (!p.contains("shell_radii") || !p.at("shell_radii").is_array() || p.at("shell_radii").size() != size_t(g.shells))
        throw Error(source, place + "shell_radii", "is not an array of `shells` numbers");
    for (size_t k = 0; k < size_t(g.shells); ++k) {
        const std::string at = place + "shell_radii[" + std::to_string(k) + "]";
        double rho = coordinateParam(p.at("shell_radii")[k], source, at);
        float radius = coordinateParam(rho * o.radius, source, at + " times params.radius");
        if (!(rho > 0.0) || (!g.shellRadii.empty() && !(radius > g.shellRadii.back())))
            throw Error(source, at, "shell radii are not positive and ascending");
        g.shellRadii.push_back(radius);
    }
    if (!p.contains("sharpen")) throw Error(source, place + "sharpen", "is missing");
    g.sharpen = coordinateParam(p.at("sharpen"), source, place + "sharpen");
    if (!(g.sharpen >= 1.0f && g.sharpen <= 100.0f)) throw Error(source, place + "sharpen", "is outside 1..100");
    if (!p.contains("source_power") || !p.at("source_power").is_array() || p.at("source_power").size() != 3)
        throw Error(source, place + "source_power", "is not an array of 3 numbers");
    if (!p.contains("source_fiv") || !p.at("source_fiv").is_array() || p.at("source_fiv").size() != 3)
        throw Error(source, place + "source_fiv", "is not an array of 3 arrays of 3 numbers");
    for (size_t c = 0; c < 3; ++c) {
        const std::string at = place + "source_power[" + std::to_string(c) + "]";
        g.power[c] = coordinateParam(p.at("source_power")[c], source, at);
        if (!(g.power[c] >= 0.0f)) throw Error(source, at, "is negative");
        const nlohmann::json& row = p.at("source_fiv")[c];
        if (!row.is_array() || row.size() != 3)
            throw Error(source, place + "source_fiv[" + std::to_string(c) + "]", "is not an array of 3 numbers");
        double length2 = 0.0;
        for (size_t a = 0; a < 3; ++a) {
            g.fiv[3 * c + a] = coordinateParam(row[a], source, place + "source_fiv[" + std::to_string(c) + "][" +
                                                                   std::to_string(a) + "]");
            length2 += double(g.fiv[3 * c + a]) * g.fiv[3 * c + a];
        }
        // A sum of power times unit directions is no longer than the power.
        if (std::sqrt(length2) > 1.001 * double(g.power[c]) + 1e-30)
            throw Error(source, place + "source_fiv[" + std::to_string(c) + "]", "is longer than source_power");
    }
    if (stringParam(fraction, "env") != o.envHash)
        throw Error(source, place + "env", "differs from the main grid's environment");
    g.fraction = fraction.data;
    g.valid.assign(valid.integers.begin(), valid.integers.end());
    return g;
}

} // namespace

FivOccluder fivOccluder(const Bundle& bundle, const std::string& source, uint32_t object) {
    const Layer* header = findObjectLayer(bundle, "fiv", object);
    if (!header) throw Error(source, objectLayerName("fiv", object), "layer is missing (not a FIV bundle from `prt fiv`)");
    FivOccluder o;
    o.azimuth = intParam(*header, "azimuth", source, 3, 4096);
    o.polar = intParam(*header, "polar", source, 2, 2049);
    o.shells = intParam(*header, "shells", source, 1, 1024);
    uint64_t rows = uint64_t(o.azimuth) * o.polar * o.shells;
    const Layer& fiv = fivLayer(bundle, "fiv", object, "fiv_occluded_rgb", FivStorage::Float, {rows, 3, 3}, source);
    const Layer& power = fivLayer(bundle, "fiv_power", object, "occluded_power_rgb", FivStorage::Float, {rows, 3}, source);
    const Layer& valid = fivLayer(bundle, "fiv_valid", object, "fiv_valid", FivStorage::Uint8, {rows}, source);
    for (uint32_t v : valid.integers)
        if (v > 1) throw Error(source, objectLayerName("fiv_valid", object), "holds a value other than 0 and 1");
    const std::string place = objectLayerName("fiv", object) + ", params.";
    const nlohmann::json& p = fiv.params;
    if (!p.contains("radius")) throw Error(source, place + "radius", "is missing");
    o.radius = coordinateParam(p.at("radius"), source, place + "radius");
    if (!(o.radius > 0.0f)) throw Error(source, place + "radius", "is not positive");
    if (!p.contains("centre") || !p.at("centre").is_array() || p.at("centre").size() != 3)
        throw Error(source, place + "centre", "is not an array of 3 numbers");
    for (int c = 0; c < 3; ++c)
        o.centre[c] = coordinateParam(p.at("centre")[size_t(c)], source, place + "centre[" + std::to_string(c) + "]");
    if (!p.contains("shell_radii") || !p.at("shell_radii").is_array() || p.at("shell_radii").size() != size_t(o.shells))
        throw Error(source, place + "shell_radii", "is not an array of `shells` numbers");
    for (size_t k = 0; k < size_t(o.shells); ++k) {
        const std::string at = place + "shell_radii[" + std::to_string(k) + "]";
        double rho = coordinateParam(p.at("shell_radii")[k], source, at);
        float radius = coordinateParam(rho * o.radius, source, at + " times params.radius");
        if (!(rho > 0.0) || (!o.shellRadii.empty() && !(radius > o.shellRadii.back())))
            throw Error(source, at, "shell radii are not positive and ascending");
        o.shellRadii.push_back(radius);
    }
    o.fiv = fiv.data;
    o.power = power.data;
    o.valid.assign(valid.integers.begin(), valid.integers.end());
    o.envHash = stringParam(fiv, "env");
    if (object == 0 && findObjectLayer(bundle, "fiv_self", 0)) {
        const Layer& self = fivLayer(bundle, "fiv_self", 0, "self_shadowed_irradiance_rgb", FivStorage::Float,
                                     {uint64_t(bundle.mesh.vertexCount()), 3}, source);
        for (float v : self.data)
            if (v < 0.0f) throw Error(source, "fiv_self", "holds a negative irradiance");
        o.selfIrradiance = self.data;
    }
    const bool hasSources = findObjectLayer(bundle, "fiv_source_grid", object) != nullptr;
    if (hasSources != (findObjectLayer(bundle, "fiv_source_valid", object) != nullptr))
        throw Error(source, objectLayerName(hasSources ? "fiv_source_valid" : "fiv_source_grid", object),
                    "layer is missing (fiv_source_grid and fiv_source_valid come together)");
    if (hasSources) o.sources = sourceGrid(bundle, source, object, o);
    return o;
}

FivLighting fivLighting(const Bundle& bundle, const std::string& source, uint32_t object) {
    const Layer* header = findObjectLayer(bundle, "difmap", object);
    if (!header) throw Error(source, objectLayerName("difmap", object), "layer is missing (not a FIV bundle from `prt fiv`)");
    FivLighting l;
    l.difmapSize = intParam(*header, "size", source, 1, 1024);
    const Layer& difmap = fivLayer(bundle, "difmap", object, "irradiance_cube_rgb", FivStorage::Float,
                                   {6 * uint64_t(l.difmapSize) * l.difmapSize, 3}, source);
    const Layer& env = fivLayer(bundle, "fiv_env", object, "fiv_environment_rgb", FivStorage::Float, {1, 3, 3}, source);
    l.difmap = difmap.data;
    std::copy(env.data.begin(), env.data.end(), l.fivEnv);
    l.envHash = stringParam(difmap, "env");
    return l;
}

void fivDifmap(const FivLighting& lighting, const float n[3], float out[3]) {
    int axis = 0;
    for (int c = 1; c < 3; ++c)
        if (std::abs(n[c]) > std::abs(n[axis])) axis = c;
    int face = 2 * axis + (n[axis] < 0.0f ? 1 : 0);
    float depth = std::abs(n[axis]);
    if (!(depth > 0.0f)) {
        std::fill(out, out + 3, 0.0f);
        return;
    }
    int size = lighting.difmapSize;
    const sh::CubeFace& f = sh::kCubeFaces[face];
    const float right[3] = {float(f.right[0]), float(f.right[1]), float(f.right[2])};
    const float up[3] = {float(f.up[0]), float(f.up[1]), float(f.up[2])};
    float a = dot3(right, n) / depth, b = dot3(up, n) / depth;
    float x = std::clamp((a + 1.0f) * 0.5f * size - 0.5f, 0.0f, float(size - 1));
    float y = std::clamp((1.0f - b) * 0.5f * size - 0.5f, 0.0f, float(size - 1));
    int x0 = std::min(int(x), size - 1), y0 = std::min(int(y), size - 1);
    int x1 = std::min(x0 + 1, size - 1), y1 = std::min(y0 + 1, size - 1);
    float tx = x - x0, ty = y - y0;
    const float* base = &lighting.difmap[3 * size_t(face) * size * size];
    for (int c = 0; c < 3; ++c) {
        float top = (1 - tx) * base[3 * (size_t(y0) * size + x0) + c] + tx * base[3 * (size_t(y0) * size + x1) + c];
        float bottom = (1 - tx) * base[3 * (size_t(y1) * size + x0) + c] + tx * base[3 * (size_t(y1) * size + x1) + c];
        out[c] = (1 - ty) * top + ty * bottom;
    }
}

namespace {

// The lookup both grids share: the eight corners around `offset` (angles bilinear, periodic in azimuth; shells
// linear in r with r_k^2 weights), handed to `gather` (which sums the usable ones and returns their weight); when
// none is usable, the nearest shells further out, four corners at a time. `scale` receives the factor that
// renormalises the sum and divides by rho^2. Returns false when no usable sample exists along the way out.
template <class Gather>
bool gridLookup(int azimuth, int polar, int shells, const std::vector<float>& r, const float offset[3], Gather gather,
                double& scale) {
    // In double: a float squared distance overflows for offsets past ~1.8e19.
    const double length = std::sqrt(double(offset[0]) * offset[0] + double(offset[1]) * offset[1] +
                                    double(offset[2]) * offset[2]);
    float distance = float(length);
    float u[3] = {0, 1, 0};
    if (length > 0.0)
        for (int c = 0; c < 3; ++c) u[c] = float(offset[c] / length);
    float theta = std::acos(std::clamp(u[1], -1.0f, 1.0f));
    float phi = std::atan2(u[0], -u[2]);
    if (phi < 0.0f) phi += float(2.0 * kPi);
    float fj = theta / float(kPi) * float(polar - 1);
    int j0 = std::clamp(int(fj), 0, polar - 2);
    float tj = std::clamp(fj - float(j0), 0.0f, 1.0f);
    float fi = phi / float(2.0 * kPi) * float(azimuth);
    int i0 = int(fi);
    float ti = std::clamp(fi - float(i0), 0.0f, 1.0f);
    i0 %= azimuth;
    int i1 = (i0 + 1) % azimuth;

    // Shell: interpolate rho^2 FIV (which tends to a constant far away) between the shells around `distance`.
    int k0, k1;
    float tk;
    if (distance <= r.front()) {
        k0 = k1 = 0, tk = 0.0f;
    } else if (distance >= r.back()) {
        k0 = k1 = shells - 1, tk = 0.0f;
    } else {
        k1 = int(std::upper_bound(r.begin(), r.end(), distance) - r.begin());
        k0 = k1 - 1;
        tk = (distance - r[size_t(k0)]) / (r[size_t(k1)] - r[size_t(k0)]);
    }
    // rho^2 FIV interpolated, then divided by rho^2: the weights carry r_k^2 and the 1 / rho^2 comes last, in
    // double, so a far occluder's tiny value underflows to 0 (it hides nothing) rather than every weight.
    const double inverse2 = distance > r.front() ? 1.0 / (length * length) : 1.0 / (double(r.front()) * r.front());
    auto rowOf = [&](int k, int j, int i) { return (size_t(k) * polar + size_t(j)) * azimuth + size_t(i); };
    auto shellWeight = [&](int k) { return r[size_t(k)] * r[size_t(k)]; };
    float angular[4] = {(1 - ti) * (1 - tj), ti * (1 - tj), (1 - ti) * tj, ti * tj};
    Corner corners[8];
    int ks[2] = {k0, k1};
    float kt[2] = {1 - tk, tk};
    for (int s = 0; s < 2; ++s) {
        float w = kt[s] * shellWeight(ks[s]);
        corners[4 * s + 0] = {rowOf(ks[s], j0, i0), w * angular[0]};
        corners[4 * s + 1] = {rowOf(ks[s], j0, i1), w * angular[1]};
        corners[4 * s + 2] = {rowOf(ks[s], j0 + 1, i0), w * angular[2]};
        corners[4 * s + 3] = {rowOf(ks[s], j0 + 1, i1), w * angular[3]};
    }
    // The weights sum to sum_s kt[s] shellWeight; renormalise to that sum over the usable corners.
    float full = kt[0] * shellWeight(k0) + kt[1] * shellWeight(k1);
    float used = gather(corners, 8);
    if (used <= 1e-6f * full) {
        // All eight inside the occluder: step outwards until a shell has usable corners.
        used = 0.0f;
        for (int k = k1 + 1; k < shells && used <= 0.0f; ++k) {
            full = shellWeight(k);
            for (int c = 0; c < 4; ++c) corners[c].row = rowOf(k, c < 2 ? j0 : j0 + 1, c % 2 ? i1 : i0), corners[c].weight = full * angular[c];
            used = gather(corners, 4);
        }
        if (used <= 0.0f) return false;
    }
    scale = double(full) / double(used) * inverse2;
    return true;
}

} // namespace

bool fivLookup(const FivOccluder& o, const float offset[3], float fiv[9], float power[3]) {
    double scale = 0.0;
    if (!gridLookup(o.azimuth, o.polar, o.shells, o.shellRadii, offset,
                    [&](const Corner* corners, int count) { return gather(o, corners, count, fiv, power); }, scale))
        return false;
    for (int e = 0; e < 9; ++e) fiv[e] = float(fiv[e] * scale);
    for (int e = 0; e < 3; ++e) power[e] = float(power[e] * scale);
    return true;
}

bool fivSourceLookup(const FivSourceGrid& g, const float offset[3], float* fraction) {
    if (g.azimuth <= 0 || g.shellRadii.empty()) return false;
    float sum = 0.0f;
    auto gatherFraction = [&](const Corner* corners, int count) {
        float total = 0.0f;
        sum = 0.0f;
        for (int c = 0; c < count; ++c) {
            if (corners[c].weight <= 0.0f || !g.valid[corners[c].row]) continue;
            sum += corners[c].weight * g.fraction[corners[c].row];
            total += corners[c].weight;
        }
        return total;
    };
    double scale = 0.0;
    if (!gridLookup(g.azimuth, g.polar, g.shells, g.shellRadii, offset, gatherFraction, scale)) return false;
    *fraction = float(std::clamp(double(sum) * scale, 0.0, 1.0));
    return true;
}

void fivIrradiance(const FivLighting& lighting, const FivInstance* instances, size_t instanceCount,
                   const FivInstance* self, const float* positions, const float* normals, size_t count,
                   const FivShadeOptions& options, float* irradiance) {
    struct Hidden {
        float direction[3];
        float angularRadius, disc;
        float value[3];
    };
    std::vector<Hidden> hidden(instanceCount);
    for (size_t point = 0; point < count; ++point) {
        const float* p = &positions[3 * point];
        const float* n = &normals[3 * point];
        float total[3], unoccluded[3];
        fivDifmap(lighting, n, total);
        std::copy(total, total + 3, unoccluded);
        float fiv[9], power[3], offset[3];
        if (self && self->selfIrradiance) {
            std::copy(&self->selfIrradiance[3 * point], &self->selfIrradiance[3 * point] + 3, unoccluded);
        } else if (self) {
            const FivOccluder& o = *self->occluder;
            for (int c = 0; c < 3; ++c) offset[c] = o.centre[c] + self->translation[c] - p[c];
            if (fivLookup(o, offset, fiv, power)) {
                for (int c = 0; c < 3; ++c) unoccluded[c] = dot3(n, &lighting.fivEnv[3 * c]) - dot3(n, &fiv[3 * c]);
                float f = 1.0f; // the grid holds the rest of the map: its sources come back signed, as FIV_self held them
                if (o.sources.azimuth > 0) {
                    float g = fivSourceLookup(o.sources, offset, &f) ? sharpened(f, o.sources.sharpen) : 1.0f;
                    for (int c = 0; c < 3; ++c) unoccluded[c] -= g * dot3(n, &o.sources.fiv[3 * c]);
                }
            }
        }
        float visible = 1.0f, sumHidden = 0.0f, sourceIrradiance[3] = {0, 0, 0}; // the sources' term
        size_t used = 0;
        for (size_t j = 0; j < instanceCount; ++j) {
            const FivOccluder& o = *instances[j].occluder;
            for (int c = 0; c < 3; ++c) offset[c] = o.centre[c] + instances[j].translation[c] - p[c];
            float d = dot3(n, offset);
            if (d <= -o.radius) continue; // case C: wholly behind the tangent plane
            if (o.sources.azimuth > 0) { // rays decided it: no partial correction
                float f = 1.0f;
                float g = fivSourceLookup(o.sources, offset, &f) ? sharpened(f, o.sources.sharpen) : 1.0f;
                visible *= 1.0f - g, sumHidden += g;
                for (int c = 0; c < 3; ++c) sourceIrradiance[c] = std::max(sourceIrradiance[c], dot3(n, &o.sources.fiv[3 * c]));
            }
            Hidden& h = hidden[used];
            if (!fivLookup(o, offset, fiv, power)) {
                std::copy(total, total + 3, h.value); // the point lies inside the occluder
            } else {
                occludedIrradiance(n, fiv, power, d, o.radius, options.partial, h.value);
            }
            if (h.value[0] <= 0.0f && h.value[1] <= 0.0f && h.value[2] <= 0.0f) continue;
            float distance = float(std::sqrt(double(offset[0]) * offset[0] + double(offset[1]) * offset[1] +
                                             double(offset[2]) * offset[2]));
            for (int c = 0; c < 3; ++c) h.direction[c] = distance > 0.0f ? offset[c] / distance : 0.0f;
            h.angularRadius = distance > o.radius ? std::asin(o.radius / distance) : float(kPi / 2);
            float green = std::sqrt(dot3(&fiv[3], &fiv[3]));
            if (options.overlap == FivOverlap::Cap && green > 0.0f && power[1] > 0.0f) {
                float cosSigma = std::clamp(2.0f * green / power[1] - 1.0f, 0.0f, 1.0f);
                h.angularRadius = std::max(std::acos(cosSigma), 1e-4f);
                for (int c = 0; c < 3; ++c) h.direction[c] = fiv[3 + c] / green;
            }
            h.disc = float(kPi) * h.angularRadius * h.angularRadius;
            ++used;
        }
        float occluded[3] = {0, 0, 0};
        if (options.overlap == FivOverlap::Paper || options.overlap == FivOverlap::Cap) {
            float largest[3] = {0, 0, 0};
            for (size_t a = 0; a < used; ++a)
                for (int c = 0; c < 3; ++c) occluded[c] += hidden[a].value[c], largest[c] = std::max(largest[c], hidden[a].value[c]);
            for (size_t a = 0; a < used; ++a)
                for (size_t b = a + 1; b < used; ++b) {
                    float cosine = std::clamp(dot3(hidden[a].direction, hidden[b].direction), -1.0f, 1.0f);
                    float reach = hidden[a].angularRadius + hidden[b].angularRadius;
                    if (reach < float(kPi) && cosine <= std::cos(reach)) continue;
                    double lens = discOverlap(hidden[a].angularRadius, hidden[b].angularRadius,
                                              angleBetween(hidden[a].direction, hidden[b].direction));
                    float share = float(lens / (hidden[a].disc + hidden[b].disc));
                    for (int c = 0; c < 3; ++c) occluded[c] -= share * (hidden[a].value[c] + hidden[b].value[c]);
                }
            for (int c = 0; c < 3; ++c) occluded[c] = std::max(occluded[c], largest[c]);
        } else {
            for (size_t a = 0; a < used; ++a) {
                float covered = 0.0f;
                if (options.overlap == FivOverlap::Shared)
                    for (size_t b = 0; b < used; ++b) {
                        if (b == a) continue;
                        float cosine = std::clamp(dot3(hidden[a].direction, hidden[b].direction), -1.0f, 1.0f);
                        float reach = hidden[a].angularRadius + hidden[b].angularRadius;
                        if (reach < float(kPi) && cosine <= std::cos(reach)) continue;
                        covered += float(discOverlap(hidden[a].angularRadius, hidden[b].angularRadius,
                                                     angleBetween(hidden[a].direction, hidden[b].direction)) /
                                         hidden[a].disc);
                    }
                for (int c = 0; c < 3; ++c) occluded[c] += hidden[a].value[c] / (1.0f + covered);
            }
        }
        const float share = options.overlap == FivOverlap::None ? std::min(sumHidden, 1.0f) : 1.0f - visible;
        for (int c = 0; c < 3; ++c) occluded[c] += share * sourceIrradiance[c];
        float* out = &irradiance[3 * point];
        for (int c = 0; c < 3; ++c) out[c] = std::clamp(unoccluded[c] - occluded[c], 0.0f, std::max(total[c], 0.0f));
    }
}

} // namespace prt
