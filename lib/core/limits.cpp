// Caps on what a file may claim, checked before anything is allocated for it, and on the threads a stage asks for.
#include "core.h"

#include <cerrno>
#include <cmath>
#include <algorithm>
#include <cstdlib>
#include <thread>

namespace prt {

uint64_t maxElements() {
    const char* text = std::getenv("PRT_MAX_ELEMENTS");
    if (!text || !*text) return kDefaultMaxElements;
    errno = 0;
    char* end = nullptr;
    unsigned long long value = std::strtoull(text, &end, 10);
    if (errno != 0 || *end != '\0' || value == 0 || text[0] == '-')
        throw Error("", "PRT_MAX_ELEMENTS", "'" + std::string(text) + "' is not a positive integer", kExitUsage);
    return uint64_t(value);
}

void checkElementCount(uint64_t count, const std::string& what, const std::string& file, const std::string& place) {
    uint64_t limit = maxElements();
    if (count <= limit) return;
    throw Error(file, place,
                "claims " + std::to_string(count) + " " + what + ", above the limit of " + std::to_string(limit) +
                    " (PRT_MAX_ELEMENTS; set PRT_MAX_ELEMENTS=N in the environment to raise it)");
}

uint64_t checkedProduct(const std::vector<uint64_t>& factors, const std::string& what, const std::string& file,
                        const std::string& place) {
    uint64_t product = 1;
    bool overflow = false;
    for (uint64_t factor : factors) {
        if (factor != 0 && product > UINT64_MAX / factor) overflow = true;
        product *= factor;
    }
    bool zero = false;
    for (uint64_t factor : factors) zero = zero || factor == 0;
    if (overflow && !zero)
        throw Error(file, place, "claims more than 2^64 " + what + ", above the limit of " + std::to_string(maxElements()) +
                                     " (PRT_MAX_ELEMENTS; set PRT_MAX_ELEMENTS=N in the environment to raise it)");
    if (zero) return 0;
    checkElementCount(product, what, file, place);
    return product;
}

int arenaConcurrency(int threads) {
    if (threads <= 0) return -1;
    return std::min(threads, std::max(1, int(std::thread::hardware_concurrency())));
}

void requireFiniteResult(const float* values, size_t count, size_t rowLength, const std::string& path) {
    for (size_t i = 0; i < count; ++i)
        if (!std::isfinite(values[i]))
            throw Error(path, "row " + std::to_string(i / std::max<size_t>(rowLength, 1)) + ", column " +
                                  std::to_string(i % std::max<size_t>(rowLength, 1)),
                        "the result is not finite, so nothing was written: an input's values overflow float on the "
                        "way (a map texel, a light or a coefficient near 3e38?)",
                        kExitInput);
}

} // namespace prt
