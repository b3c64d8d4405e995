// Internal to lib/transfer: what the transfer passes and the bare yardstick share, so both cast the same rays.
#pragma once

#include "raycast.h"
#include "transfer.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace prt::rays {

// Vertices per work block: the unit of parallel work and of hit-record storage. Fixed, so that no result
// depends on how blocks land on threads.
inline constexpr size_t kBlockVertices = 256;

// The shared direction set in the local frame (normal = +z): uniform-hemisphere Hammersley, cos(theta_k) = z_k =
// (k + 0.5) / N exactly as computed in double and rounded once.
struct Hemisphere {
    std::vector<float> x, y, z;
};
Hemisphere hemisphere(int samples);

// Where a receiver's rays start and the frame they are turned into: columns tangent, bitangent, normal.
// The frame turns about the normal by an angle hashed from (seed, key); a mesh vertex's key is its index.
struct Fan {
    double tangent[3], bitangent[3], normal[3];
    float origin[3];
    float axes[9]; // tangent, bitangent, normal as floats, for the ray directions
};
// Needs a nonzero normal (normalised here) and finite position.
// Rays start at spawnOrigin(position, spawnNormal, offset) (lib/raycast); spawnNormal null: the normal.
Fan fan(const float position[3], const float normal[3], const float* spawnNormal, uint64_t key, uint64_t seed,
        float offset);

// The receivers a per-vertex pass works on: vertices [begin, end) of the mesh, keys their indices, albedo the
// mesh's per-vertex albedo unless it has none or options.albedoOverride (then null: options.albedo).
// `spawn` is their spawn normals, spawnNormals(mesh, begin, end) (lib/raycast), and must outlive the receivers, or
// null for a pass that casts no ray (a bounce gathers at recorded hits).
Receivers vertexReceivers(const TriMesh& mesh, const TransferOptions& options, size_t begin, size_t end,
                          const float* spawn);

// Receiver i's rotation key.
inline uint64_t receiverKey(const Receivers& receivers, size_t i) {
    return receivers.keys ? receivers.keys[i] : receivers.firstKey + i;
}

// Receivers [first, first + count) of `receivers` as a view of their own, keys kept.
Receivers receiverSlice(const Receivers& receivers, size_t first, size_t count);

// Receiver i's fan.
inline Fan fan(const Receivers& receivers, size_t i, uint64_t seed, float offset) {
    return fan(&receivers.positions[3 * i], &receivers.normals[3 * i],
               receivers.spawnNormals ? &receivers.spawnNormals[3 * i] : nullptr, receiverKey(receivers, i), seed, offset);
}

// Checks receivers as computeTransferAt needs them: positions finite, normals nonzero and finite, albedo in
// [0, 1]. Throws prt::Error(kExitInput) naming "receiver i".
void validateReceivers(const Receivers& receivers);

// The ray of sample k of a fan, ready for rtcOccluded1 / rtcIntersect1.
inline void setRay(const Fan& fan, const Hemisphere& set, int k, float offset, RTCRay& ray) {
    // The fan's origin is spawnOrigin(position, normal, offset): the shared spawn rule (lib/raycast).
    float sx = set.x[k], sy = set.y[k], sz = set.z[k];
    const float* a = fan.axes;
    spawnRay(ray, fan.origin, a[0] * sx + a[3] * sy + a[6] * sz, a[1] * sx + a[4] * sy + a[7] * sz,
             a[2] * sx + a[5] * sy + a[8] * sz);
}

// Checks what every pass relies on: normals present and nonzero, indices in range, finite positions.
// Throws prt::Error(kExitInput) naming the first offending element.
void validateMesh(const TriMesh& mesh);

// The options' vertex range clipped to the mesh.
void clipRange(const TriMesh& mesh, const TransferOptions& options, size_t& begin, size_t& end);

} // namespace prt::rays
