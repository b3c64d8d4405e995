// The JSON types of a glTF 2.0 file's core properties (the glTF 2.0 JSON schema, types only), checked once for
// every glTF prt reads (loadModelFromBytes). tinygltf reads a property of the wrong type as absent, so without this
// check `"pbrMetallicRoughness": ["not an object"]` would bake a black, fully metallic material, and a scene bundle
// would carry `"name": 42` on to every viewer as the asset it was given.
#include "bundle_internal.h"

#include "json_input.h"

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace prt::detail {

namespace {

using nlohmann::json;

// What a property holds. Id: a glTF index or enum value (an integer in 0..2^31 - 1); Offset / Count: a byte offset
// or stride (an integer >= 0) / a length or count (>= 1), up to 2^53, so that sizes past what prt reads reach the
// readers' own caps and messages; Object / Objects: one / an array of objects of `kind`; IdMap: an object of ids
// (attributes, morph targets); IdMaps: an array of those.
enum class Type { String, Number, Id, Offset, Count, Boolean, Numbers, Ids, Strings, Object, Objects, IdMap, IdMaps };

struct Kind;
struct Property {
    const char* key;
    Type type;
    const Kind* kind = nullptr; // Object and Objects
};
struct Kind {
    std::vector<Property> properties;
};

// The core schema's objects, leaves first. Every object may also hold `extensions` (an object of objects) and
// `extras` (anything), and most a `name` (a string): checked for every object below.
const Kind kTextureInfo{{{"index", Type::Id}, {"texCoord", Type::Id}}};
const Kind kNormalTextureInfo{{{"index", Type::Id}, {"texCoord", Type::Id}, {"scale", Type::Number}}};
const Kind kOcclusionTextureInfo{{{"index", Type::Id}, {"texCoord", Type::Id}, {"strength", Type::Number}}};
const Kind kPbr{{{"baseColorFactor", Type::Numbers}, {"baseColorTexture", Type::Object, &kTextureInfo},
                 {"metallicFactor", Type::Number}, {"roughnessFactor", Type::Number},
                 {"metallicRoughnessTexture", Type::Object, &kTextureInfo}}};
const Kind kMaterial{{{"pbrMetallicRoughness", Type::Object, &kPbr},
                      {"normalTexture", Type::Object, &kNormalTextureInfo},
                      {"occlusionTexture", Type::Object, &kOcclusionTextureInfo},
                      {"emissiveTexture", Type::Object, &kTextureInfo}, {"emissiveFactor", Type::Numbers},
                      {"alphaMode", Type::String}, {"alphaCutoff", Type::Number}, {"doubleSided", Type::Boolean}}};
const Kind kSparseIndices{{{"bufferView", Type::Id}, {"byteOffset", Type::Offset}, {"componentType", Type::Id}}};
const Kind kSparseValues{{{"bufferView", Type::Id}, {"byteOffset", Type::Offset}}};
const Kind kSparse{{{"count", Type::Count}, {"indices", Type::Object, &kSparseIndices},
                    {"values", Type::Object, &kSparseValues}}};
const Kind kAccessor{{{"bufferView", Type::Id}, {"byteOffset", Type::Offset}, {"componentType", Type::Id},
                      {"normalized", Type::Boolean}, {"count", Type::Count}, {"type", Type::String},
                      {"max", Type::Numbers}, {"min", Type::Numbers}, {"sparse", Type::Object, &kSparse}}};
const Kind kChannelTarget{{{"node", Type::Id}, {"path", Type::String}}};
const Kind kChannel{{{"sampler", Type::Id}, {"target", Type::Object, &kChannelTarget}}};
const Kind kAnimationSampler{{{"input", Type::Id}, {"interpolation", Type::String}, {"output", Type::Id}}};
const Kind kAnimation{{{"channels", Type::Objects, &kChannel}, {"samplers", Type::Objects, &kAnimationSampler}}};
const Kind kAsset{{{"copyright", Type::String}, {"generator", Type::String}, {"version", Type::String},
                   {"minVersion", Type::String}}};
const Kind kBuffer{{{"uri", Type::String}, {"byteLength", Type::Count}}};
const Kind kBufferView{{{"buffer", Type::Id}, {"byteOffset", Type::Offset}, {"byteLength", Type::Count},
                        {"byteStride", Type::Offset}, {"target", Type::Id}}};
const Kind kOrthographic{{{"xmag", Type::Number}, {"ymag", Type::Number}, {"zfar", Type::Number}, {"znear", Type::Number}}};
const Kind kPerspective{{{"aspectRatio", Type::Number}, {"yfov", Type::Number}, {"zfar", Type::Number},
                         {"znear", Type::Number}}};
const Kind kCamera{{{"orthographic", Type::Object, &kOrthographic}, {"perspective", Type::Object, &kPerspective},
                    {"type", Type::String}}};
const Kind kImage{{{"uri", Type::String}, {"mimeType", Type::String}, {"bufferView", Type::Id}}};
const Kind kPrimitive{{{"attributes", Type::IdMap}, {"indices", Type::Id}, {"material", Type::Id}, {"mode", Type::Id},
                       {"targets", Type::IdMaps}}};
const Kind kMesh{{{"primitives", Type::Objects, &kPrimitive}, {"weights", Type::Numbers}}};
const Kind kNode{{{"camera", Type::Id}, {"children", Type::Ids}, {"skin", Type::Id}, {"matrix", Type::Numbers},
                  {"mesh", Type::Id}, {"rotation", Type::Numbers}, {"scale", Type::Numbers},
                  {"translation", Type::Numbers}, {"weights", Type::Numbers}}};
const Kind kSampler{{{"magFilter", Type::Id}, {"minFilter", Type::Id}, {"wrapS", Type::Id}, {"wrapT", Type::Id}}};
const Kind kScene{{{"nodes", Type::Ids}}};
const Kind kSkin{{{"inverseBindMatrices", Type::Id}, {"skeleton", Type::Id}, {"joints", Type::Ids}}};
const Kind kTexture{{{"sampler", Type::Id}, {"source", Type::Id}}};
const Kind kRoot{{{"extensionsUsed", Type::Strings}, {"extensionsRequired", Type::Strings},
                  {"accessors", Type::Objects, &kAccessor}, {"animations", Type::Objects, &kAnimation},
                  {"asset", Type::Object, &kAsset}, {"buffers", Type::Objects, &kBuffer},
                  {"bufferViews", Type::Objects, &kBufferView}, {"cameras", Type::Objects, &kCamera},
                  {"images", Type::Objects, &kImage}, {"materials", Type::Objects, &kMaterial},
                  {"meshes", Type::Objects, &kMesh}, {"nodes", Type::Objects, &kNode},
                  {"samplers", Type::Objects, &kSampler}, {"scene", Type::Id}, {"scenes", Type::Objects, &kScene},
                  {"skins", Type::Objects, &kSkin}, {"textures", Type::Objects, &kTexture}}};

[[noreturn]] void wrongType(const json& value, const std::string& file, const std::string& place, const char* expected) {
    throw Error(file, place, std::string("expected ") + expected + " (glTF 2.0 schema), got " + jsonTypeName(value) +
                                 " " + jsonExcerpt(value, 40));
}

void checkId(const json& value, const std::string& file, const std::string& place) {
    jsonIntegerValue(value, file, place, 0, std::numeric_limits<int32_t>::max());
}
void checkSize(const json& value, const std::string& file, const std::string& place, int64_t min) {
    jsonIntegerValue(value, file, place, min, int64_t(1) << 53);
}

void checkArray(const json& value, const std::string& file, const std::string& place, const char* expected,
                const std::function<void(const json&, const std::string&)>& element) {
    if (!value.is_array()) wrongType(value, file, place, expected);
    for (size_t i = 0; i < value.size(); ++i) element(value[i], place + "[" + std::to_string(i) + "]");
}

void checkIdMap(const json& value, const std::string& file, const std::string& place) {
    if (!value.is_object()) wrongType(value, file, place, "an object of indices");
    for (const auto& [key, id] : value.items()) checkId(id, file, place + "." + key);
}

// `object` against `kind`, then its name, extensions and extras. The schema nests at most 5 objects deep, so the
// recursion is bounded by it, not by the file.
void checkObject(const json& object, const Kind& kind, const std::string& file, const std::string& place) {
    if (!object.is_object()) wrongType(object, file, place, "an object");
    const std::string prefix = place.empty() ? "" : place + ".";
    if (object.contains("name") && !object["name"].is_string())
        wrongType(object["name"], file, prefix + "name", "a string");
    if (object.contains("extensions")) {
        const json& extensions = object["extensions"];
        if (!extensions.is_object()) wrongType(extensions, file, prefix + "extensions", "an object");
        for (const auto& [name, extension] : extensions.items())
            if (!extension.is_object()) wrongType(extension, file, prefix + "extensions." + name, "an object");
    }
    for (const Property& property : kind.properties) {
        auto found = object.find(property.key);
        if (found == object.end()) continue;
        const json& value = *found;
        const std::string at = prefix + property.key;
        switch (property.type) {
        case Type::String:
            if (!value.is_string()) wrongType(value, file, at, "a string");
            break;
        case Type::Number: jsonNumberValue(value, file, at); break;
        case Type::Id: checkId(value, file, at); break;
        case Type::Offset: checkSize(value, file, at, 0); break;
        case Type::Count: checkSize(value, file, at, 1); break;
        case Type::Boolean:
            if (!value.is_boolean()) wrongType(value, file, at, "true or false");
            break;
        case Type::Numbers:
            checkArray(value, file, at, "an array of numbers",
                       [&](const json& e, const std::string& p) { jsonNumberValue(e, file, p); });
            break;
        case Type::Ids:
            checkArray(value, file, at, "an array of indices",
                       [&](const json& e, const std::string& p) { checkId(e, file, p); });
            break;
        case Type::Strings:
            checkArray(value, file, at, "an array of strings", [&](const json& e, const std::string& p) {
                if (!e.is_string()) wrongType(e, file, p, "a string");
            });
            break;
        case Type::Object: checkObject(value, *property.kind, file, at); break;
        case Type::Objects:
            checkArray(value, file, at, "an array of objects",
                       [&](const json& e, const std::string& p) { checkObject(e, *property.kind, file, p); });
            break;
        case Type::IdMap: checkIdMap(value, file, at); break;
        case Type::IdMaps:
            checkArray(value, file, at, "an array of objects of indices",
                       [&](const json& e, const std::string& p) { checkIdMap(e, file, p); });
            break;
        }
    }
}

} // namespace

void checkGltfTypes(const nlohmann::json& root, const std::string& file) { checkObject(root, kRoot, file, ""); }

} // namespace prt::detail
