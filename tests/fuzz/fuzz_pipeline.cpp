// libFuzzer harness: the pipeline TOML parser (parsePipeline: syntax, schema, wiring, cycles).
#include "fuzz_util.h"
#include "pipeline.h"

#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    prt::fuzz::expectOnlyErrors([&] { prt::parsePipeline(text, "fuzz.toml"); });
    return 0;
}
