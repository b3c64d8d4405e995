// libFuzzer harness: an environment map through OpenImageIO's OpenEXR reader, as `prt envsh` reads it.
#include "fuzz_util.h"
#include "image.h"
#include "image_library.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    static bool once = (prt::setImageLibraryThreads(1), true); // one thread: deterministic, and no pool per input
    (void)once;
    std::string path = prt::fuzz::writeInput(data, size, "exr");
    prt::fuzz::expectOnlyErrors([&] { prt::readEnvironmentMap(path); });
    return 0;
}
