// libFuzzer harness: prt-lights JSON (`prt envlight`'s output) through readHybridLightingJson, the one reader that
// `prt relight --lights` and `prt reference --lights` share; a file it accepts is also rotated, as relight does.
// Seeds: tests/fuzz/corpus/lights (a valid file, wrong types, deep nesting).
#include "fuzz_util.h"
#include "runtime.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string path = prt::fuzz::writeInput(data, size, "lights.json");
    prt::fuzz::expectOnlyErrors([&] {
        prt::HybridLighting lighting = prt::readHybridLightingJson(path);
        const double quarterTurn[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
        prt::HybridLighting rotated = prt::rotateHybridLighting(lighting, quarterTurn);
        if (rotated.lights.size() != lighting.lights.size() || rotated.residual.size() != lighting.residual.size())
            std::abort();
    });
    return 0;
}
