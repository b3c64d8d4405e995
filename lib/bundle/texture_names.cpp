// The names a bake gives its external textures (isBakeTextureName in bundle.h).
#include "bundle.h"

#include <cctype>
#include <cstdint>
#include <string>

namespace prt {

bool isBakeTextureName(const std::string& name, const std::string& bundleStem) {
    if (name.size() <= bundleStem.size() + 1 || name.compare(0, bundleStem.size() + 1, bundleStem + ".") != 0) return false;
    const std::string rest = name.substr(bundleStem.size() + 1); // KIND.HEX.EXT
    const size_t extensionDot = rest.rfind('.');
    if (extensionDot == std::string::npos || extensionDot < 18 || rest[extensionDot - 17] != '.') return false;
    const std::string extension = rest.substr(extensionDot + 1);
    const std::string hex = rest.substr(extensionDot - 16, 16);
    std::string kind = rest.substr(0, extensionDot - 17);
    if (extension != "exr" && extension != "png" && extension != "json") return false;
    for (char c : hex)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    if (kind.size() == 14 || kind.size() == 12) { // transfer.T000, bounce.T000
        const std::string plane = kind.substr(kind.size() - 5);
        if (plane[0] != '.' || plane[1] != 'T' || !std::isdigit(uint8_t(plane[2])) || !std::isdigit(uint8_t(plane[3])) ||
            !std::isdigit(uint8_t(plane[4])))
            return false;
        kind.resize(kind.size() - 5);
    }
    return kind == "transfer" || kind == "bounce" || kind == "surface" || kind == "normal";
}

} // namespace prt
