// FIV scene bundles: a receiver, occluder types with their grids, and instances, in one version-2 bundle that an
// engine loads as a whole (fiv.h, docs/fiv.md "Scene bundles").
#include "fiv.h"

#include "core.h"
#include "runtime.h"

#include <set>

namespace prt::fiv {

namespace {

const char* const kGridLayers[] = {"fiv", "fiv_power", "fiv_valid"};
const char* const kLightingLayers[] = {"difmap", "fiv_env"};
const char* const kSourceLayers[] = {"fiv_source_grid", "fiv_source_valid"};

const Layer& requireFivLayer(const Bundle& bundle, const char* name, const std::string& source) {
    const Layer* layer = findObjectLayer(bundle, name, 0);
    if (!layer) throw Error(source, name, "layer is missing on object 0 (not a FIV bundle from `prt fiv`)");
    return *layer;
}

// The checks `prt fivshade` runs on the same file (runtime.h fivOccluder and fivLighting: every layer's type,
// count and shape, the params typed and in range), so no scene is written that fivshade would refuse.
std::string validatedEnvHash(const Bundle& bundle, const std::string& source) {
    fivOccluder(bundle, source, 0);
    fivLighting(bundle, source, 0);
    const Layer& fiv = requireFivLayer(bundle, "fiv", source);
    if (!fiv.params.contains("env") || !fiv.params.at("env").is_string())
        throw Error(source, "fiv", "params.env (the environment's hash) is missing or not a string");
    return fiv.params.at("env").get<std::string>();
}

} // namespace

Bundle fivSceneBundle(const Bundle& receiver, const std::string& receiverSource, const std::vector<SceneType>& types,
                      const std::vector<ScenePlacement>& placements, const Bundle* self,
                      const std::string& selfSource) {
    if (types.empty() && !self)
        throw Error("", "--occluder", "a scene needs at least one occluder or the receiver's own grid", kExitUsage);
    if (receiver.mesh.positions.empty() || receiver.mesh.normals.size() != receiver.mesh.positions.size())
        throw Error(receiverSource, "mesh", "has no vertex normals (prt meshprep adds them)");
    checkFivPoints(receiver.mesh.positions, receiverSource);
    Bundle scene;
    scene.mesh = receiver.mesh;
    scene.meshName = "receiver";
    scene.meshRole = "receiver";
    scene.producer = {{"tool", "prt"}, {"stage", "fivscene"}};
    scene.inputs = {{"receiver", hashFile(receiverSource)}};
    scene.convention = {{"instances", "occluder object k's vertex p sits at p + translation (world units)"},
                        {"layers", "object k's grid layers are fiv.k, fiv_power.k and fiv_valid.k (object 0: the "
                                   "receiver's own grid, for self-shadowing); difmap and fiv_env once"}};
    std::string sceneEnv;
    auto checkEnv = [&](const Bundle& bundle, const std::string& source) {
        std::string hash = validatedEnvHash(bundle, source);
        if (sceneEnv.empty()) sceneEnv = hash;
        if (hash != sceneEnv)
            throw Error(source, "fiv", "was reduced under another environment than the scene's other grids");
    };
    auto copyLayers = [&](const Bundle& bundle, const std::string& source, uint32_t object, bool lighting) {
        for (const char* name : kGridLayers) {
            Layer layer = requireFivLayer(bundle, name, source);
            layer.name = objectLayerName(name, object);
            layer.object = object;
            scene.layers.push_back(std::move(layer));
        }
        // Optional: the sources' own grid (decision 13), renamed like the grid.
        for (const char* name : kSourceLayers)
            if (findObjectLayer(bundle, name, 0)) {
                Layer layer = requireFivLayer(bundle, name, source);
                layer.name = objectLayerName(name, object);
                layer.object = object;
                scene.layers.push_back(std::move(layer));
            }
        if (!lighting) return;
        for (const char* name : kLightingLayers) {
            Layer layer = requireFivLayer(bundle, name, source);
            layer.object = object;
            scene.layers.push_back(std::move(layer));
        }
    };
    if (self) {
        if (self->mesh.positions != receiver.mesh.positions)
            throw Error(selfSource, "mesh", "is not the receiver's mesh: --self needs the receiver's own FIV grid");
        checkEnv(*self, selfSource);
        copyLayers(*self, selfSource, 0, types.empty());
        // The receiver's exact self-shadowing at its vertices (decision 14) holds for this mesh, normals included.
        if (findObjectLayer(*self, "fiv_self", 0)) {
            if (self->mesh.normals == receiver.mesh.normals) {
                Layer layer = requireFivLayer(*self, "fiv_self", selfSource);
                layer.object = 0;
                scene.layers.push_back(std::move(layer));
            } else {
                logWarn(selfSource + ": fiv_self is for other vertex normals than " + receiverSource +
                        "'s; the scene shades self-shadowing through the grid");
            }
        }
        scene.inputs["self"] = hashFile(selfSource);
    }
    std::set<std::string> names = {"receiver"};
    nlohmann::json typeHashes = nlohmann::json::array();
    for (size_t t = 0; t < types.size(); ++t) {
        const SceneType& type = types[t];
        checkEnv(*type.bundle, type.source);
        std::string name = type.name.empty() ? "occluder" : type.name;
        for (int suffix = 2; !names.insert(name).second; ++suffix)
            name = (type.name.empty() ? "occluder" : type.name) + "-" + std::to_string(suffix);
        scene.objects.push_back({name, "occluder", type.bundle->mesh});
        copyLayers(*type.bundle, type.source, uint32_t(t + 1), t == 0);
        typeHashes.push_back(hashFile(type.source));
    }
    scene.inputs["occluders"] = typeHashes;
    scene.instances.push_back({"receiver", 0, {0, 0, 0}});
    for (size_t i = 0; i < placements.size(); ++i) {
        const ScenePlacement& placement = placements[i];
        if (placement.type >= types.size())
            throw Error("", "--at", "placement " + std::to_string(i) + " names no occluder", kExitUsage);
        scene.instances.push_back({scene.objects[placement.type].name + "#" + std::to_string(i),
                                   uint32_t(placement.type + 1), placement.translation});
    }
    return scene;
}

} // namespace prt::fiv
