// libFuzzer harness: loadMesh on a .glb file (the pre-check, then OpenMesh or tinygltf).
#include "fuzz_util.h"
#include "mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string path = prt::fuzz::writeInput(data, size, "glb");
    prt::fuzz::expectOnlyErrors([&] {
        prt::TriMesh mesh = prt::loadMesh(path, nullptr);
        prt::validateMesh(mesh, path);
    });
    return 0;
}
