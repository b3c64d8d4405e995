#include "scene.h"

namespace prt {

TriMesh mergeMeshes(const std::vector<TriMesh>& parts) {
    TriMesh merged;
    bool normals = true, texcoords = true, albedo = true;
    for (const TriMesh& part : parts) {
        normals = normals && !part.normals.empty();
        texcoords = texcoords && !part.texcoords.empty();
        albedo = albedo && !part.albedo.empty();
    }
    for (const TriMesh& part : parts) {
        uint32_t offset = uint32_t(merged.vertexCount());
        merged.positions.insert(merged.positions.end(), part.positions.begin(), part.positions.end());
        if (normals) merged.normals.insert(merged.normals.end(), part.normals.begin(), part.normals.end());
        if (texcoords) merged.texcoords.insert(merged.texcoords.end(), part.texcoords.begin(), part.texcoords.end());
        if (albedo) merged.albedo.insert(merged.albedo.end(), part.albedo.begin(), part.albedo.end());
        for (uint32_t index : part.indices) merged.indices.push_back(offset + index);
    }
    return merged;
}

} // namespace prt
