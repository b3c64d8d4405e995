// The shared Hammersley direction set and the per-vertex frames.
#include "rays.h"

#include "core.h"

#include <algorithm>
#include <numbers>
#include <string>

namespace prt::rays {

static double radicalInverse2(uint32_t bits) {
    bits = (bits << 16) | (bits >> 16);
    bits = ((bits & 0x55555555u) << 1) | ((bits & 0xAAAAAAAAu) >> 1);
    bits = ((bits & 0x33333333u) << 2) | ((bits & 0xCCCCCCCCu) >> 2);
    bits = ((bits & 0x0F0F0F0Fu) << 4) | ((bits & 0xF0F0F0F0u) >> 4);
    bits = ((bits & 0x00FF00FFu) << 8) | ((bits & 0xFF00FF00u) >> 8);
    return double(bits) * 0x1p-32;
}

Hemisphere hemisphere(int samples) {
    Hemisphere set;
    set.x.resize(samples);
    set.y.resize(samples);
    set.z.resize(samples);
    for (int k = 0; k < samples; ++k) {
        double cosTheta = (k + 0.5) / samples;
        double sinTheta = std::sqrt(1.0 - cosTheta * cosTheta);
        double phi = 2.0 * std::numbers::pi * radicalInverse2(uint32_t(k));
        set.x[k] = float(sinTheta * std::cos(phi));
        set.y[k] = float(sinTheta * std::sin(phi));
        set.z[k] = float(cosTheta);
    }
    return set;
}

// SplitMix64 finaliser: a well-mixed 64-bit hash of a 64-bit key.
static uint64_t mix64(uint64_t key) {
    key += 0x9E3779B97F4A7C15ull;
    key = (key ^ (key >> 30)) * 0xBF58476D1CE4E5B9ull;
    key = (key ^ (key >> 27)) * 0x94D049BB133111EBull;
    return key ^ (key >> 31);
}

Fan fan(const float position[3], const float normal[3], const float* spawnNormal, uint64_t key, uint64_t seed,
        float offset) {
    Fan f;
    const float* p = position;
    const float* m = normal;
    double length = std::sqrt(double(m[0]) * m[0] + double(m[1]) * m[1] + double(m[2]) * m[2]);
    double n[3] = {m[0] / length, m[1] / length, m[2] / length};

    // Branchless orthonormal basis about n (Duff et al. 2017), right-handed: t x b = n.
    double sign = std::copysign(1.0, n[2]);
    double a = -1.0 / (sign + n[2]);
    double b = n[0] * n[1] * a;
    double t0[3] = {1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]};
    double b0[3] = {b, sign + n[1] * n[1] * a, -n[1]};

    double angle = 2.0 * std::numbers::pi * double(mix64(seed ^ mix64(key)) >> 11) * 0x1p-53;
    double c = std::cos(angle), s = std::sin(angle);
    for (int i = 0; i < 3; ++i) {
        f.tangent[i] = c * t0[i] + s * b0[i];
        f.bitangent[i] = -s * t0[i] + c * b0[i];
        f.normal[i] = n[i];
        // spawnOrigin (lib/raycast), in double.
        f.origin[i] = float(p[i] + double(offset) * (spawnNormal ? double(spawnNormal[i]) : n[i]));
        f.axes[i] = float(f.tangent[i]);
        f.axes[3 + i] = float(f.bitangent[i]);
        f.axes[6 + i] = float(n[i]);
    }
    return f;
}

void validateMesh(const TriMesh& mesh) {
    size_t count = mesh.vertexCount();
    if (count == 0 || mesh.triangleCount() == 0) throw Error("", "mesh", "has no triangles");
    if (mesh.normals.size() != mesh.positions.size())
        throw Error("", "mesh", "has no per-vertex normals (run `prt meshprep` first)");
    if (!mesh.albedo.empty() && mesh.albedo.size() != mesh.positions.size())
        throw Error("", "mesh albedo", "has " + std::to_string(mesh.albedo.size()) + " values for " +
                                           std::to_string(count) + " vertices");
    for (size_t v = 0; v < count; ++v) {
        const float* p = &mesh.positions[3 * v];
        const float* n = &mesh.normals[3 * v];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw Error("", "vertex " + std::to_string(v), "position is not finite");
        double length2 = double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2];
        if (!(length2 > 1e-12) || !std::isfinite(length2))
            throw Error("", "vertex " + std::to_string(v), "normal is zero or not finite");
    }
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= count)
            throw Error("", "triangle " + std::to_string(i / 3),
                        "index " + std::to_string(mesh.indices[i]) + " >= vertex count " + std::to_string(count));
}

Receivers vertexReceivers(const TriMesh& mesh, const TransferOptions& options, size_t begin, size_t end,
                          const float* spawn) {
    Receivers receivers;
    receivers.positions = mesh.positions.data() + 3 * begin;
    receivers.normals = mesh.normals.data() + 3 * begin;
    receivers.spawnNormals = spawn;
    if (!mesh.albedo.empty() && !options.albedoOverride) receivers.albedo = mesh.albedo.data() + 3 * begin;
    receivers.firstKey = begin;
    receivers.count = end - begin;
    return receivers;
}

Receivers receiverSlice(const Receivers& receivers, size_t first, size_t count) {
    Receivers slice = receivers;
    slice.positions += 3 * first;
    slice.normals += 3 * first;
    if (slice.spawnNormals) slice.spawnNormals += 3 * first;
    if (slice.albedo) slice.albedo += 3 * first;
    if (slice.keys) slice.keys += first;
    else slice.firstKey += first;
    slice.count = count;
    return slice;
}

void validateReceivers(const Receivers& receivers) {
    if (receivers.count > 0 && (!receivers.positions || !receivers.normals))
        throw Error("", "receivers", "positions and normals are required");
    for (size_t i = 0; i < receivers.count; ++i) {
        const float* p = &receivers.positions[3 * i];
        const float* n = &receivers.normals[3 * i];
        std::string place = "receiver " + std::to_string(i);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw Error("", place, "position is not finite");
        double length2 = double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2];
        if (!(length2 > 1e-12) || !std::isfinite(length2)) throw Error("", place, "normal is zero or not finite");
        if (receivers.albedo)
            for (int c = 0; c < 3; ++c)
                if (!(receivers.albedo[3 * i + c] >= 0.0f && receivers.albedo[3 * i + c] <= 1.0f))
                    throw Error("", place, "albedo outside [0, 1]");
    }
}

void clipRange(const TriMesh& mesh, const TransferOptions& options, size_t& begin, size_t& end) {
    end = std::min(options.vertexEnd, mesh.vertexCount());
    begin = std::min(options.vertexBegin, end);
}

} // namespace prt::rays
