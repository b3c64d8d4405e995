// prt core: untrusted JSON, bounded and typed. Every reader of a JSON file or chunk that prt did not just write
// itself (bundle glTF JSON, prt-lights, prt-sh, shard headers, texel sidecars) goes through these, so that
//   - nesting depth and size are bounded before any parser (tinygltf's is recursive) or dump() sees the text;
//   - a member of the wrong JSON type is an Error naming the file, the key and the type expected, never a
//     nlohmann type_error (exit 1), and integers are range-checked before they are narrowed;
//   - a value quoted in a message is cut to a few dozen characters.
#pragma once

#include "core.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>

namespace prt {

// Size caps of prt's own JSON formats, checked on the file before it is read.
inline constexpr size_t kMaxLightsJsonBytes = size_t(8) << 20; // prt-lights: 4096 lights at ~1 KB, residual, options
inline constexpr size_t kMaxShJsonBytes = size_t(8) << 20;     // prt-sh: 32 bands of RGB rows are ~80 KB
inline constexpr size_t kMaxSidecarJsonBytes = size_t(1) << 20; // prt-texel-u8: one entry per coefficient

// Deepest nesting of arrays and objects any prt JSON input may have. prt's own files nest at most ~6 deep.
inline constexpr int kMaxJsonDepth = 64;

// Scans `text` once, without recursion, and throws Error(file, place, ...) when it is longer than maxBytes or
// nests arrays and objects deeper than maxDepth. Brackets inside strings (escapes included) are not counted. It
// checks shape only: text that passes may still not be JSON (the parser says so).
void checkJsonShape(std::string_view text, const std::string& file, const std::string& place, size_t maxBytes,
                    int maxDepth = kMaxJsonDepth);

// checkJsonShape, then nlohmann's parse. Throws Error(file, place, "not JSON: ...") for a syntax error.
nlohmann::json parseJsonBounded(std::string_view text, const std::string& file, const std::string& place,
                                size_t maxBytes, int maxDepth = kMaxJsonDepth);

// Reads and parses the JSON file `path` of at most maxBytes: the size is checked on the file before it is read
// (a folder or a missing file gives readFileBytes's message), then parseJsonBounded.
nlohmann::json readJsonFile(const std::string& path, size_t maxBytes, int maxDepth = kMaxJsonDepth);

// A value for an error message: its compact dump, cut to maxChars characters with "..." appended when longer.
std::string jsonExcerpt(const nlohmann::json& value, size_t maxChars = 80);

// The JSON type of a value in words ("a string", "an array", "null", ...), for messages.
std::string jsonTypeName(const nlohmann::json& value);

// ---- typed members ------------------------------------------------------------------------------------------
// Each reads object[key] and throws Error(file, PLACE, problem) when `object` is not an object, the key is
// missing, or the value has the wrong type or range; PLACE is `place` + "." + key (or key alone when place is
// empty) and the problem names the type expected and the value found (excerpted).
const nlohmann::json& jsonMember(const nlohmann::json& object, const std::string& key, const std::string& file,
                                 const std::string& place);
std::string jsonString(const nlohmann::json& object, const std::string& key, const std::string& file,
                       const std::string& place);
// A finite number; with a float target, also finite as a float (use jsonFloat).
double jsonNumber(const nlohmann::json& object, const std::string& key, const std::string& file,
                  const std::string& place);
float jsonFloat(const nlohmann::json& object, const std::string& key, const std::string& file,
                const std::string& place);
// An integer (no fraction, no exponent form that nlohmann reads as a float) in [min, max], compared before any
// narrowing, so 2^32 + 3 is refused by an int's range instead of wrapping to 3.
int64_t jsonInteger(const nlohmann::json& object, const std::string& key, const std::string& file,
                    const std::string& place, int64_t min, int64_t max);
bool jsonBool(const nlohmann::json& object, const std::string& key, const std::string& file,
              const std::string& place);
// The same checks on a value already in hand (an array element); `place` names it whole ("lights[3]").
int64_t jsonIntegerValue(const nlohmann::json& value, const std::string& file, const std::string& place,
                         int64_t min, int64_t max);
double jsonNumberValue(const nlohmann::json& value, const std::string& file, const std::string& place);

} // namespace prt
