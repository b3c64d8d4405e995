// libFuzzer harness: readNpy (header, shape, size checks).
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string path = prt::fuzz::writeInput(data, size, "npy");
    prt::fuzz::expectOnlyErrors([&] {
        std::vector<size_t> shape;
        prt::readNpy(path, &shape);
    });
    return 0;
}
