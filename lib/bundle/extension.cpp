#include "bundle_internal.h"

#include "core.h"
#include "utf8.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <limits>

namespace prt::detail {

using nlohmann::json;

static bool isEmptyValue(const json& value) {
    return value.is_null() || ((value.is_object() || value.is_array()) && value.empty());
}

json storableJson(const json& value, const std::string& file, const std::string& place) {
    auto refuse = [&](const std::string& problem) { throw Error(file, place, problem, kExitFailure); };
    switch (value.type()) {
    case json::value_t::object: {
        json out = json::object();
        for (const auto& [key, member] : value.items()) {
            if (!isUtf8(key)) refuse("object key is not UTF-8");
            json stored = storableJson(member, file, place + "." + key);
            if (!isEmptyValue(stored)) out[key] = std::move(stored);
        }
        return out;
    }
    case json::value_t::array: {
        json out = json::array();
        for (size_t i = 0; i < value.size(); ++i) {
            std::string elementPlace = place + "[" + std::to_string(i) + "]";
            json stored = storableJson(value[i], file, elementPlace);
            if (isEmptyValue(stored)) throw Error(file, elementPlace, "glTF cannot store a null or empty array element", kExitFailure);
            out.push_back(std::move(stored));
        }
        return out;
    }
    case json::value_t::number_integer:
    case json::value_t::number_unsigned: {
        // Doubles hold integers exactly up to 2^53; beyond that the stored value would differ from the given one.
        constexpr double kExactLimit = 9007199254740992.0;
        double asDouble = value.is_number_unsigned() ? double(value.get<uint64_t>()) : double(value.get<int64_t>());
        if (asDouble >= std::numeric_limits<int32_t>::min() && asDouble <= std::numeric_limits<int32_t>::max()) return value;
        if (std::fabs(asDouble) > kExactLimit) refuse("integer beyond 2^53 cannot be stored exactly");
        return json(asDouble);
    }
    case json::value_t::number_float:
        if (!std::isfinite(value.get<double>())) refuse("JSON cannot store NaN or infinity");
        return value;
    case json::value_t::binary:
        refuse("binary JSON values cannot be stored");
        return {};
    case json::value_t::string:
        if (!isUtf8(value.get_ref<const std::string&>())) refuse("string is not UTF-8");
        return value;
    default: // boolean, null
        return value;
    }
}

tinygltf::Value toGltfValue(const json& storable) {
    switch (storable.type()) {
    case json::value_t::object: {
        tinygltf::Value::Object members;
        for (const auto& [key, member] : storable.items()) members.emplace(key, toGltfValue(member));
        return tinygltf::Value(std::move(members));
    }
    case json::value_t::array: {
        tinygltf::Value::Array elements;
        for (const json& element : storable) elements.push_back(toGltfValue(element));
        return tinygltf::Value(std::move(elements));
    }
    case json::value_t::number_integer:
    case json::value_t::number_unsigned: return tinygltf::Value(storable.get<int>());
    case json::value_t::number_float: return tinygltf::Value(storable.get<double>());
    case json::value_t::string: return tinygltf::Value(storable.get<std::string>());
    case json::value_t::boolean: return tinygltf::Value(storable.get<bool>());
    default: return tinygltf::Value();
    }
}

// Python's repr(float): the shortest digits that read back to `value`, positional when the decimal exponent is
// in [-4, 16), else d.ddde+XX with at least two exponent digits.
static void appendNumber(double value, std::string& out) {
    char text[64];
    char* end = std::to_chars(text, text + sizeof(text) - 1, value, std::chars_format::scientific).ptr; // "-1.25e+17"
    *end = '\0';
    char* mark = std::find(text, end, 'e');
    int exponent = std::atoi(mark + 1);
    std::string digits;
    for (char* c = text; c != mark; ++c)
        if (std::isdigit((unsigned char)*c)) digits.push_back(*c);
    if (text[0] == '-') out.push_back('-');
    if (exponent < -4 || exponent >= 16) {
        out.push_back(digits[0]);
        if (digits.size() > 1) out.append(".").append(digits, 1);
        char suffix[16];
        std::snprintf(suffix, sizeof(suffix), "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
        out.append(suffix);
    } else if (exponent < 0) {
        out.append("0.").append(size_t(-exponent - 1), '0').append(digits);
    } else if (digits.size() <= size_t(exponent) + 1) {
        out.append(digits).append(exponent + 1 - digits.size(), '0').append(".0");
    } else {
        out.append(digits, 0, exponent + 1).append(".").append(digits, exponent + 1);
    }
}

static void appendString(const std::string& text, std::string& out) {
    out += '"';
    for (unsigned char c : text) {
        switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\b': out += "\\b"; break;
        case '\f': out += "\\f"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        case '\t': out += "\\t"; break;
        default:
            if (c < 0x20) {
                char escape[8];
                std::snprintf(escape, sizeof(escape), "\\u%04x", c);
                out += escape;
            } else {
                out += char(c);
            }
        }
    }
    out += '"';
}

void appendCanonicalJson(const json& value, std::string& out) {
    switch (value.type()) {
    case json::value_t::object: {
        out += '{';
        for (auto member = value.begin(); member != value.end(); ++member) { // std::map order: UTF-8 byte order
            if (member != value.begin()) out += ',';
            appendString(member.key(), out);
            out += ':';
            appendCanonicalJson(member.value(), out);
        }
        out += '}';
        return;
    }
    case json::value_t::array:
        out += '[';
        for (size_t i = 0; i < value.size(); ++i) {
            if (i > 0) out += ',';
            appendCanonicalJson(value[i], out);
        }
        out += ']';
        return;
    case json::value_t::string: appendString(value.get_ref<const std::string&>(), out); return;
    case json::value_t::number_float: appendNumber(value.get<double>(), out); return;
    default: out += value.dump(); return; // integers, booleans, null
    }
}

std::string canonicalExtensionText(json extension) {
    extension.erase("checksum");
    std::string text;
    appendCanonicalJson(extension, text);
    return text;
}

std::string extensionChecksum(const std::vector<unsigned char>& buffer, const json& extension) {
    StreamHash hash;
    hash.add(buffer.data(), buffer.size());
    std::string canonical = canonicalExtensionText(extension);
    hash.add(canonical.data(), canonical.size());
    return hash.digest();
}

} // namespace prt::detail
