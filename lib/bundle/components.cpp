// Layer component types and objects: what version 2 added to the data model (docs/bundle.md, "Component types").
#include "bundle_internal.h"

#include "core.h"

#include <bit>
#include <cstring>

namespace prt {

uint16_t floatToHalf(float value) {
    uint32_t bits = std::bit_cast<uint32_t>(value);
    uint32_t sign = (bits >> 16) & 0x8000u;
    uint32_t magnitude = bits & 0x7fffffffu;
    if (magnitude >= 0x7f800000u) // infinity stays infinity, NaN stays a quiet NaN
        return uint16_t(sign | 0x7c00u | (magnitude > 0x7f800000u ? 0x200u : 0u));
    if (magnitude >= 0x477ff000u) return uint16_t(sign | 0x7c00u); // rounds past 65504
    if (magnitude < 0x38800000u) {
        // Subnormal half (or zero): the value in units of 2^-24, rounded to nearest even.
        if (magnitude < 0x33000000u) return uint16_t(sign); // below half the smallest subnormal
        uint32_t exponent = magnitude >> 23;
        uint32_t mantissa = (magnitude & 0x7fffffu) | 0x800000u;
        uint32_t shift = 126 - exponent; // 14 .. 24 bits shifted out
        uint32_t half = mantissa >> shift;
        uint32_t rest = mantissa & ((1u << shift) - 1);
        uint32_t halfway = 1u << (shift - 1);
        if (rest > halfway || (rest == halfway && (half & 1u))) ++half;
        return uint16_t(sign | half);
    }
    // Normal: rebias the exponent (127 -> 15) and round the 13 dropped mantissa bits to nearest even; a carry
    // into the exponent is the correct rounding.
    uint32_t half = (magnitude - 0x38000000u) >> 13;
    uint32_t rest = magnitude & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (half & 1u))) ++half;
    return uint16_t(sign | half);
}

float halfToFloat(uint16_t half) {
    uint32_t sign = uint32_t(half & 0x8000u) << 16;
    uint32_t exponent = (half >> 10) & 0x1fu;
    uint32_t mantissa = half & 0x3ffu;
    if (exponent == 0x1f) return std::bit_cast<float>(sign | 0x7f800000u | (mantissa << 13));
    if (exponent == 0) {
        // Subnormal: mantissa * 2^-24, exact in float.
        float value = float(mantissa) * 5.9604644775390625e-8f;
        return sign ? -value : value;
    }
    return std::bit_cast<float>(sign | ((exponent + 112) << 23) | (mantissa << 13));
}

const TriMesh& objectMesh(const Bundle& bundle, uint32_t object) {
    if (object == 0) return bundle.mesh;
    if (object > bundle.objects.size())
        throw Error("", "bundle", "object " + std::to_string(object) + " does not exist: the bundle has " +
                                      std::to_string(bundle.objects.size() + 1) + " objects", kExitFailure);
    return bundle.objects[object - 1].mesh;
}

namespace detail {

size_t componentSize(const std::string& componentType) {
    if (componentType == "float32" || componentType == "uint32") return 4;
    if (componentType == "float16" || componentType == "uint16") return 2;
    if (componentType == "uint8") return 1;
    return 0;
}

bool isFloatComponent(const std::string& componentType) {
    return componentType == "float32" || componentType == "float16";
}

void decodeIntegers(const unsigned char* bytes, size_t count, size_t size, uint32_t* out) {
    for (size_t i = 0; i < count; ++i) {
        if (size == 1) {
            out[i] = bytes[i];
        } else if (size == 2) {
            uint16_t value;
            std::memcpy(&value, bytes + 2 * i, 2);
            out[i] = value;
        } else {
            std::memcpy(&out[i], bytes + 4 * i, 4);
        }
    }
}

} // namespace detail
} // namespace prt
