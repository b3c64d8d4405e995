// Untrusted JSON: the shape check before parsing, and typed members with messages that name key and type.
#include "json_input.h"

#include <cmath>
#include <sys/stat.h>

namespace prt {

void checkJsonShape(std::string_view text, const std::string& file, const std::string& place, size_t maxBytes,
                    int maxDepth) {
    if (text.size() > maxBytes)
        throw Error(file, place, "JSON of " + std::to_string(text.size()) + " bytes, above the limit of " +
                                     std::to_string(maxBytes) + " bytes for this kind of file");
    int depth = 0;
    bool inString = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\') ++i; // the escaped character, whatever it is, cannot end the string
            else if (c == '"') inString = false;
            continue;
        }
        if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > maxDepth)
                throw Error(file, place, "JSON nests arrays and objects deeper than " + std::to_string(maxDepth) +
                                             " levels (at byte " + std::to_string(i) + ")");
        } else if (c == ']' || c == '}') {
            if (depth > 0) --depth; // unbalanced text is the parser's to refuse
        }
    }
}

nlohmann::json parseJsonBounded(std::string_view text, const std::string& file, const std::string& place,
                                size_t maxBytes, int maxDepth) {
    checkJsonShape(text, file, place, maxBytes, maxDepth);
    try {
        return nlohmann::json::parse(text.begin(), text.end());
    } catch (const nlohmann::json::exception& e) {
        std::string what = e.what();
        if (what.size() > 200) what = what.substr(0, 200) + "...";
        throw Error(file, place, "not JSON: " + what);
    }
}

nlohmann::json readJsonFile(const std::string& path, size_t maxBytes, int maxDepth) {
    struct stat info;
    if (stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode) && uint64_t(info.st_size) > maxBytes)
        throw Error(path, "", "file of " + std::to_string(uint64_t(info.st_size)) + " bytes, above the limit of " +
                                  std::to_string(maxBytes) + " bytes for this kind of file");
    return parseJsonBounded(readFileBytes(path), path, "", maxBytes, maxDepth);
}

std::string jsonExcerpt(const nlohmann::json& value, size_t maxChars) {
    // error_handler replace: a string with invalid UTF-8 is quoted, not thrown about.
    std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() <= maxChars) return text;
    return text.substr(0, maxChars) + "...";
}

std::string jsonTypeName(const nlohmann::json& value) {
    switch (value.type()) {
    case nlohmann::json::value_t::null: return "null";
    case nlohmann::json::value_t::object: return "an object";
    case nlohmann::json::value_t::array: return "an array";
    case nlohmann::json::value_t::string: return "a string";
    case nlohmann::json::value_t::boolean: return "a boolean";
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: return "an integer";
    case nlohmann::json::value_t::number_float: return "a number";
    case nlohmann::json::value_t::binary: return "binary data";
    case nlohmann::json::value_t::discarded: return "nothing";
    }
    return "unknown";
}

namespace {

std::string memberPlace(const std::string& place, const std::string& key) {
    return place.empty() ? key : place + "." + key;
}

[[noreturn]] void wrongType(const nlohmann::json& value, const std::string& file, const std::string& place,
                            const std::string& expected) {
    throw Error(file, place, "expected " + expected + ", got " + jsonTypeName(value) + " " + jsonExcerpt(value));
}

} // namespace

const nlohmann::json& jsonMember(const nlohmann::json& object, const std::string& key, const std::string& file,
                                 const std::string& place) {
    if (!object.is_object()) wrongType(object, file, place.empty() ? "(top level)" : place, "an object");
    auto found = object.find(key);
    if (found == object.end()) throw Error(file, memberPlace(place, key), "is missing");
    return *found;
}

std::string jsonString(const nlohmann::json& object, const std::string& key, const std::string& file,
                       const std::string& place) {
    const nlohmann::json& value = jsonMember(object, key, file, place);
    if (!value.is_string()) wrongType(value, file, memberPlace(place, key), "a string");
    return value.get<std::string>();
}

double jsonNumberValue(const nlohmann::json& value, const std::string& file, const std::string& place) {
    if (!value.is_number()) wrongType(value, file, place, "a number");
    double x = value.get<double>();
    if (!std::isfinite(x)) throw Error(file, place, "value " + jsonExcerpt(value) + " is not finite");
    return x;
}

double jsonNumber(const nlohmann::json& object, const std::string& key, const std::string& file,
                  const std::string& place) {
    return jsonNumberValue(jsonMember(object, key, file, place), file, memberPlace(place, key));
}

float jsonFloat(const nlohmann::json& object, const std::string& key, const std::string& file,
                const std::string& place) {
    double x = jsonNumber(object, key, file, place);
    if (!std::isfinite(float(x)))
        throw Error(file, memberPlace(place, key), "value " + jsonExcerpt(object.at(key)) + " is outside the float range");
    return float(x);
}

int64_t jsonIntegerValue(const nlohmann::json& value, const std::string& file, const std::string& place,
                         int64_t min, int64_t max) {
    const std::string range = "an integer in " + std::to_string(min) + ".." + std::to_string(max);
    if (!value.is_number_integer()) wrongType(value, file, place, range);
    // Compare in the value's own representation: an unsigned above INT64_MAX must not wrap negative.
    bool inRange = value.is_number_unsigned()
                       ? max >= 0 && value.get<uint64_t>() <= uint64_t(max) && (min <= 0 || value.get<uint64_t>() >= uint64_t(min))
                       : value.get<int64_t>() >= min && value.get<int64_t>() <= max;
    if (!inRange) throw Error(file, place, "expected " + range + ", got " + jsonExcerpt(value));
    return value.is_number_unsigned() ? int64_t(value.get<uint64_t>()) : value.get<int64_t>();
}

int64_t jsonInteger(const nlohmann::json& object, const std::string& key, const std::string& file,
                    const std::string& place, int64_t min, int64_t max) {
    return jsonIntegerValue(jsonMember(object, key, file, place), file, memberPlace(place, key), min, max);
}

bool jsonBool(const nlohmann::json& object, const std::string& key, const std::string& file,
              const std::string& place) {
    const nlohmann::json& value = jsonMember(object, key, file, place);
    if (!value.is_boolean()) wrongType(value, file, memberPlace(place, key), "true or false");
    return value.get<bool>();
}

} // namespace prt
