// FIV scene bundles at run time: several occluder types and their instances in one bundle (runtime.h, docs/fiv.md
// "Scene bundles"). std, lib/bundle and lib/core only.
#include "runtime.h"

#include "core.h"

#include <cmath>

namespace prt {

bool isFivScene(const Bundle& bundle) {
    for (uint32_t k = 1; k <= bundle.objects.size(); ++k)
        if (findObjectLayer(bundle, "fiv", k)) return true;
    // A self-shadowing scene has one object; a FIV bundle from `prt fiv` names its object an occluder.
    return bundle.meshRole == "receiver" && findObjectLayer(bundle, "fiv", 0);
}

FivScene fivScene(const Bundle& bundle, const std::string& source) {
    FivScene scene;
    uint32_t objects = uint32_t(bundle.objects.size()) + 1;
    scene.grids.resize(objects);
    std::vector<bool> hasGrid(objects, false);
    bool lit = false;
    for (size_t i = 0; i < bundle.instances.size(); ++i)
        if (bundle.instances[i].object >= objects)
            throw Error(source, "instance " + std::to_string(i), "places object " +
                                    std::to_string(bundle.instances[i].object) + ", which the bundle does not hold");
    for (uint32_t k = 0; k < objects; ++k) {
        if (findObjectLayer(bundle, "fiv", k)) {
            scene.grids[k] = fivOccluder(bundle, source, k);
            hasGrid[k] = true;
        }
        if (!lit && findObjectLayer(bundle, "difmap", k)) {
            scene.lighting = fivLighting(bundle, source, k);
            lit = true;
        }
    }
    if (!lit) throw Error(source, "difmap", "layer is missing (not a FIV scene from `prt fivscene`)");
    for (uint32_t k = 0; k < objects; ++k)
        if (hasGrid[k] && scene.grids[k].envHash != scene.lighting.envHash)
            throw Error(source, objectLayerName("fiv", k), "was reduced under another environment than the scene's difmap");
    for (size_t i = 0; i < bundle.instances.size(); ++i) {
        const Instance& instance = bundle.instances[i];
        if (instance.object == 0) continue; // the receiver; its own grid is `self`
        if (!hasGrid[instance.object])
            throw Error(source, "instance " + std::to_string(i),
                        "places object " + std::to_string(instance.object) + ", which has no FIV grid");
        FivInstance placed;
        placed.occluder = &scene.grids[instance.object];
        for (int c = 0; c < 3; ++c) {
            float t = instance.translation[size_t(c)];
            if (!std::isfinite(t) || std::abs(double(t)) > kFivMaxCoordinate)
                throw Error(source, "instance " + std::to_string(i) + ", translation",
                            "is not finite or lies beyond +-" + std::to_string(int64_t(kFivMaxCoordinate)));
            placed.translation[c] = t;
        }
        scene.instances.push_back(placed);
    }
    scene.selfShadowing = hasGrid[0];
    if (scene.selfShadowing) {
        scene.self.occluder = &scene.grids[0];
        // fiv_self (fivOccluder checked it against the receiver's vertex count): the receiver is that mesh.
        if (!scene.grids[0].selfIrradiance.empty()) scene.self.selfIrradiance = scene.grids[0].selfIrradiance.data();
    }
    if (scene.instances.empty() && !scene.selfShadowing)
        throw Error(source, "instances", "place no occluder, and the receiver has no grid of its own");
    return scene;
}

} // namespace prt
