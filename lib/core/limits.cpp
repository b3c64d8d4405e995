// Memory caps on what a file may claim, checked before anything is allocated for it.
#include "core.h"

#include <cerrno>
#include <cstdlib>

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

} // namespace prt
