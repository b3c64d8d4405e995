// A scene's lightmap atlas: which texcoord set a scene bakes into, and the atlas as a per-corner layer, since a
// scene bundle keeps its asset's own vertices and texcoords (docs/bundle.md "Scene bundles").
#include "bake.h"

#include "core.h"

#include <tiny_gltf.h>

#include <map>

namespace prt {

namespace {

// Whether every placed primitive of the scene has TEXCOORD_<set>.
bool everyReceiverHas(const SceneAsset& asset, int set) {
    const std::string name = "TEXCOORD_" + std::to_string(set);
    for (const SceneReceiver& receiver : asset.receivers) {
        const tinygltf::Primitive& primitive =
            asset.source->meshes[size_t(receiver.mesh)].primitives[size_t(receiver.primitive)];
        if (!primitive.attributes.count(name)) return false;
    }
    return !asset.receivers.empty();
}

// A mesh placed by several nodes, or -1: its texcoords then address one place for several surfaces.
int sharedMesh(const SceneAsset& asset) {
    std::map<int, int> placements;
    for (const SceneReceiver& receiver : asset.receivers)
        if (++placements[receiver.mesh] > 1) return receiver.mesh;
    return -1;
}

} // namespace

std::vector<float> sceneAtlasTexcoords(const Bundle& scene, int uvSet, const std::string& path, int& chosenSet) {
    const SceneAsset& asset = *scene.asset;
    chosenSet = -1;
    if (uvSet > 1)
        throw Error(path, "--uv-set", "a scene keeps TEXCOORD_0 and TEXCOORD_1 only, not TEXCOORD_" +
                                          std::to_string(uvSet), kExitUsage);
    int shared = sharedMesh(asset);
    if (uvSet < 0) {
        if (!everyReceiverHas(asset, 1)) {
            logInfo("bake: " + path + " has no TEXCOORD_1 on every primitive: generating a lightmap atlas over the "
                    "whole scene");
            return {};
        }
        if (shared >= 0) {
            logInfo("bake: mesh " + std::to_string(shared) + " of " + path + " is placed by several nodes, so its "
                    "TEXCOORD_1 is not unique: generating a lightmap atlas over every instance");
            return {};
        }
        chosenSet = 1;
        return asset.texcoords[1];
    }
    if (!everyReceiverHas(asset, uvSet))
        throw Error(path, "--uv-set", "some primitive has no TEXCOORD_" + std::to_string(uvSet), kExitInput);
    if (shared >= 0)
        throw Error(path, "meshes[" + std::to_string(shared) + "]",
                    "is placed by several nodes, so TEXCOORD_" + std::to_string(uvSet) +
                        " maps every instance onto the same texels; a lightmap needs a unique atlas: leave out "
                        "--uv-set and prt generates one over every instance",
                    kExitInput);
    chosenSet = uvSet;
    return asset.texcoords[size_t(uvSet)];
}

Layer lightmapUvLayer(const TriMesh& atlasMesh) {
    Layer layer;
    layer.name = "lightmap_uv";
    layer.domain = "corner";
    layer.semantic = "lightmap_uv";
    layer.shape = {uint64_t(atlasMesh.indices.size()), 2};
    layer.data.resize(2 * atlasMesh.indices.size());
    for (size_t corner = 0; corner < atlasMesh.indices.size(); ++corner)
        for (int a = 0; a < 2; ++a)
            layer.data[2 * corner + a] = atlasMesh.texcoords[2 * size_t(atlasMesh.indices[corner]) + a];
    layer.params = {{"uv", "glTF's: v down; texel (x, y) of the atlas has its centre at ((x + 0.5) / width, "
                           "(y + 0.5) / height)"},
                    {"rows", "triangle corners of the flattened mesh: 3 t + k, triangles in receiver order"}};
    return layer;
}

} // namespace prt
