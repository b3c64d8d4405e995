#include "bundle_internal.h"

#include "core.h"
#include "json_input.h"

#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <algorithm>
#include <limits>
#include <set>

namespace prt {

using nlohmann::json;

static_assert(std::endian::native == std::endian::little, "GLB buffers are little-endian");

// Images stay encoded (PNG, JPEG) as the file holds them: a scene bundle writes them back unchanged, and only the
// stages that need texels decode them (lib/material, with their sizes bounded before decoding).
static bool keepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                             const unsigned char* bytes, int size, void*) {
    image->image.assign(bytes, bytes + std::max(size, 0));
    image->as_is = true;
    return true;
}

// tinygltf's file-system callbacks for external buffers: a URI is followed only when the file it names, links
// resolved, lies inside the glTF file's own folder (tinygltf also tries the working directory; that is refused
// the same way), and only up to the glTF size limit. What was refused is kept for the error message.
struct ExternalFiles {
    std::filesystem::path folder; // canonical
    std::string refused;
};

static bool insideFolder(const std::string& candidate, ExternalFiles& files) {
    if (!resolvedInside(candidate, files.folder.string()).empty()) return true;
    std::error_code error;
    std::filesystem::path resolved = std::filesystem::weakly_canonical(candidate, error);
    if (!error && files.refused.empty() && std::filesystem::exists(resolved, error)) files.refused = resolved.string();
    return false;
}

static bool externalFileExists(const std::string& candidate, void* user) {
    ExternalFiles& files = *static_cast<ExternalFiles*>(user);
    std::error_code error;
    return insideFolder(candidate, files) && std::filesystem::is_regular_file(candidate, error);
}

static std::string externalExpand(const std::string& candidate, void*) { return candidate; }

static bool readExternalFile(std::vector<unsigned char>* out, std::string* err, const std::string& candidate, void* user) {
    ExternalFiles& files = *static_cast<ExternalFiles*>(user);
    if (!insideFolder(candidate, files)) {
        if (err) *err += "outside the glTF file's folder";
        return false;
    }
    std::error_code error;
    uintmax_t size = std::filesystem::file_size(candidate, error);
    if (error || size > std::numeric_limits<unsigned int>::max()) {
        if (err) *err += error ? error.message() : "larger than 4 GiB, the glTF limit";
        return false;
    }
    std::string bytes = readFileBytes(candidate);
    out->assign(bytes.begin(), bytes.end());
    return true;
}

static bool refuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "prt never writes through a glTF reader";
    return false;
}

// `jsonText` receives the file's glTF JSON as written (a .glb's JSON chunk), which a scene keeps (asset.h).
static tinygltf::Model loadModel(const std::string& path, std::string& jsonText) {
    return detail::loadModelFromBytes(path, readFileBytes(path), jsonText);
}

} // namespace prt

namespace prt::detail {

// Why tinygltf could not read a file whose JSON (already bounded by checkJsonShape) says it is glTF 1.0 or requires
// an extension prt cannot honour, such as Draco's accessors without a buffer view: refused by name, as a file that
// loads would be. Returns where the JSON says neither (or is not JSON).
static void explainUnreadable(std::string_view jsonText, const std::string& path) {
    const nlohmann::json root = nlohmann::json::parse(jsonText, nullptr, false);
    if (!root.is_object()) return;
    if (root.contains("asset") && root["asset"].is_object() && root["asset"].contains("version") &&
        root["asset"]["version"].is_string())
        requireGltf2(root["asset"]["version"].get<std::string>(), path);
    if (!root.contains("extensionsRequired") || !root["extensionsRequired"].is_array()) return;
    std::vector<std::string> required;
    for (const nlohmann::json& name : root["extensionsRequired"])
        if (name.is_string()) required.push_back(name.get<std::string>());
    checkRequiredExtensions(required, path);
}

void checkGlbHeader(const std::string& path, uint32_t version, uint64_t declaredLength, uint64_t fileSize) {
    // A binary of glTF 1.0 (KHR_binary_glTF) lays out its header otherwise: say what it is before reading on.
    if (version != 2)
        throw Error(path, "glTF binary", "version " + std::to_string(version) + " is not supported; prt reads glTF 2.0 "
                                         "(convert the file, for example with the Khronos glTF 1.0 to 2.0 converter)");
    // The most common damage, a cut-off download or copy, gets a plain message instead of tinygltf's generic one.
    if (declaredLength > fileSize)
        throw Error(path, "glTF binary", "truncated: the header declares " + std::to_string(declaredLength) +
                                             " bytes, the file has " + std::to_string(fileSize));
    if (declaredLength < fileSize)
        throw Error(path, "glTF binary", std::to_string(fileSize - declaredLength) + " bytes past the " +
                                             std::to_string(declaredLength) + " its header declares (two files joined, "
                                             "or a copy that appended to an old one?)");
}

tinygltf::Model loadModelFromBytes(const std::string& path, const std::string& bytes, std::string& jsonText) {
    if (bytes.empty()) throw Error(path, "", "empty file");
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw Error(path, "", "larger than 4 GiB, the glTF limit");
    bool binary = bytes.compare(0, 4, "glTF") == 0;
    const std::string place = binary ? "glTF binary" : "glTF";
    if (binary && bytes.size() >= 12) {
        uint32_t head[3];
        std::memcpy(head, bytes.data(), sizeof head);
        checkGlbHeader(path, head[1], head[2], bytes.size());
    }
    // Nesting bounded before tinygltf's recursive parser sees the JSON (a GLB's first chunk).
    uint32_t jsonChunk = 0;
    if (binary && bytes.size() >= 20) std::memcpy(&jsonChunk, bytes.data() + 12, 4);
    const std::string_view json = binary ? std::string_view(bytes).substr(std::min<size_t>(20, bytes.size()), jsonChunk)
                                         : std::string_view(bytes);
    checkJsonShape(json, path, place, std::numeric_limits<unsigned int>::max());

    // External buffers and images of a .gltf lie next to the file, or, when it is a symbolic link (as `prt run`
    // links inputs into a job's folder), next to its target.
    std::error_code folderError;
    ExternalFiles files{std::filesystem::weakly_canonical(std::filesystem::absolute(path), folderError).parent_path(), ""};
    const std::string folder = files.folder.string();
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({externalFileExists, externalExpand, readExternalFile, refuseWrite, &files});
    loader.SetStoreOriginalJSONForExtrasAndExtensions(true);
    loader.SetImageLoader(keepEncodedImage, nullptr);
    tinygltf::Model model;
    std::string error, warning;
    bool loaded = false;
    try {
        loaded = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                                      unsigned(bytes.size()), folder)
                        : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), unsigned(bytes.size()), folder);
    } catch (const std::exception& e) { // tinygltf parses untrusted bytes; whatever it throws is about the file
        error = e.what();
    }
    if (loaded && binary) {
        uint32_t jsonLength = 0;
        if (bytes.size() >= 20) std::memcpy(&jsonLength, bytes.data() + 12, 4);
        jsonText = bytes.substr(20, std::min<size_t>(jsonLength, bytes.size() - std::min<size_t>(20, bytes.size())));
    } else if (loaded) {
        jsonText = bytes;
    }
    if (loaded) {
        const nlohmann::json root = nlohmann::json::parse(jsonText, nullptr, false); // tinygltf parsed it already
        if (!root.is_discarded()) checkGltfTypes(root, path);
    }
    if (!loaded) {
        explainUnreadable(json, path);
        while (!error.empty() && std::isspace((unsigned char)error.back())) error.pop_back();
        if (!files.refused.empty())
            throw Error(path, place, "an external URI resolves to " + files.refused +
                                         ", outside the file's folder; prt follows URIs only into the glTF file's own folder");
        throw Error(path, place, error.empty() ? "not a glTF file" : error);
    }
    return model;
}

} // namespace prt::detail

namespace prt {

// A member that must be a JSON object when present; absent (glTF leaves out empty objects) reads as {}.
static json objectMember(const json& parent, const char* key, const std::string& path, const std::string& place) {
    if (!parent.contains(key)) return json::object();
    if (!parent[key].is_object()) throw Error(path, place + "." + key, "is not a JSON object");
    return parent[key];
}

static std::string stringMember(const json& parent, const char* key, const std::string& path, const std::string& place) {
    if (!parent.contains(key) || !parent[key].is_string()) throw Error(path, place + "." + key, "missing or not a string");
    return parent[key].get<std::string>();
}

// One layer record. With `streamed`, the model's buffer holds only the bytes before the layers: the view is
// checked against the whole buffer's length, and its place goes to streamed->extents instead of values to the layer.
static Layer readLayer(const json& record, const tinygltf::Model& model, const Bundle& bundle, int version,
                       const std::string& path, const std::string& place, detail::StreamedBuffer* streamed) {
    auto refuse = [&](const std::string& problem) { throw Error(path, place, problem); };
    if (!record.is_object()) refuse("layer is not a JSON object");
    Layer layer;
    layer.name = stringMember(record, "name", path, place);
    layer.domain = stringMember(record, "domain", path, place);
    layer.semantic = stringMember(record, "semantic", path, place);
    layer.params = objectMember(record, "params", path, place);
    if (record.contains("object")) {
        if (version < 2) refuse("object is a version 2 member");
        if (!record["object"].is_number_unsigned() || record["object"].get<uint64_t>() > bundle.objects.size())
            refuse("object " + record["object"].dump() + " does not exist");
        layer.object = record["object"].get<uint32_t>();
    }
    if (!record.contains("shape") || !record["shape"].is_array() || record["shape"].empty()) refuse("shape is missing or empty");
    uint64_t count = 1;
    bool overflow = false;
    for (const json& extent : record["shape"]) {
        if (!extent.is_number_unsigned()) refuse("shape holds something other than non-negative integers");
        layer.shape.push_back(extent.get<uint64_t>());
        overflow = overflow || (layer.shape.back() != 0 && count > std::numeric_limits<uint64_t>::max() / layer.shape.back());
        count *= layer.shape.back();
    }
    if (overflow) refuse("shape is too large");
    checkElementCount(count, "layer values", path, place + ".shape");
    size_t vertexCount = objectMesh(bundle, layer.object).vertexCount();
    if (layer.domain == "vertex" && layer.shape[0] != vertexCount)
        refuse("vertex layer has " + std::to_string(layer.shape[0]) + " rows but the mesh has " + std::to_string(vertexCount) + " vertices");
    size_t cornerCount = objectMesh(bundle, layer.object).indices.size();
    if (layer.domain == "corner" && layer.shape[0] != cornerCount)
        refuse("corner layer has " + std::to_string(layer.shape[0]) + " rows but the mesh has " + std::to_string(cornerCount) +
               " triangle corners");

    if (!record.contains("bufferView")) {
        bool external = layer.params.contains("uri") && layer.params["uri"].is_string();
        if (count != 0 && !external) refuse("layer has neither a bufferView nor params.uri");
        if (record.contains("componentType") && record["componentType"].is_string())
            layer.componentType = record["componentType"].get<std::string>();
        if (streamed) streamed->extents->push_back({});
        return layer;
    }
    layer.componentType = record.value("componentType", "");
    size_t size = detail::componentSize(layer.componentType);
    if (version < 2 && layer.componentType != "float32") refuse("componentType must be \"float32\"");
    if (size == 0) refuse("componentType must be one of float32, float16, uint8, uint16, uint32");
    if (!record["bufferView"].is_number_unsigned() || record["bufferView"].get<uint64_t>() >= model.bufferViews.size())
        refuse("bufferView does not exist");
    const tinygltf::BufferView& view = model.bufferViews[record["bufferView"].get<size_t>()];
    if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) refuse("bufferView has no valid buffer");
    const std::vector<unsigned char>& buffer = model.buffers[view.buffer].data;
    const uint64_t bufferLength = streamed ? streamed->length : buffer.size();
    if (view.byteOffset > bufferLength || view.byteLength > bufferLength - view.byteOffset)
        refuse("bufferView reaches past the end of its buffer");
    // Checked against the view, which lies inside the file, before anything is allocated.
    if (count > view.byteLength / size || view.byteLength != count * size)
        refuse("bufferView holds " + std::to_string(view.byteLength) + " bytes, shape needs " + std::to_string(count) + " " +
               layer.componentType);
    if (streamed) {
        streamed->extents->push_back({view.byteOffset, view.byteLength, ""});
        return layer;
    }
    const unsigned char* bytes = buffer.data() + view.byteOffset;
    if (layer.componentType == "float32") {
        layer.data.resize(count);
        if (count > 0) std::memcpy(layer.data.data(), bytes, view.byteLength);
    } else if (layer.componentType == "float16") {
        layer.data.resize(count);
        for (size_t i = 0; i < count; ++i) {
            uint16_t half;
            std::memcpy(&half, bytes + 2 * i, 2);
            layer.data[i] = halfToFloat(half);
        }
    } else {
        layer.integers.resize(count);
        detail::decodeIntegers(bytes, count, size, layer.integers.data());
    }
    return layer;
}

// The PRT_bundle object, after checking its version and checksum: nothing else in it is trusted before that.
static json verifiedExtension(const tinygltf::Model& model, const std::string& path, const detail::StreamedBuffer* streamed) {
    const std::string place = kBundleExtension;
    json extension = json::parse(model.extensions_json_string).at(kBundleExtension);
    if (!extension.is_object()) throw Error(path, place, "is not a JSON object");
    json version = extension.value("version", json());
    if (!version.is_number_integer() || version.get<int64_t>() < kOldestBundleVersion || version.get<int64_t>() > kBundleVersion)
        throw Error(path, place, "version " + version.dump() + " is not supported; this build reads versions " +
                                     std::to_string(kOldestBundleVersion) + " to " + std::to_string(kBundleVersion));
    if (!extension.contains("checksum") || !extension["checksum"].is_string()) throw Error(path, place, "checksum is missing");
    static const std::vector<unsigned char> kNoBuffer;
    const std::vector<unsigned char>& buffer = model.buffers.empty() ? kNoBuffer : model.buffers[0].data;
    std::string checksum;
    if (streamed) { // the whole buffer went through streamed->hash already
        std::string canonical = detail::canonicalExtensionText(extension);
        streamed->hash->add(canonical.data(), canonical.size());
        checksum = streamed->hash->digest();
    } else {
        checksum = detail::extensionChecksum(buffer, extension);
    }
    if (extension["checksum"].get<std::string>() != checksum)
        throw Error(path, place, "checksum mismatch: the bundle is truncated or was modified");
    return extension;
}

// A version 2 bundle's objects, each from its own glTF mesh: object 0 into bundle.mesh, the rest into objects.
static void readObjects(const json& extension, const tinygltf::Model& model, const std::string& path, Bundle& bundle) {
    const std::string place = std::string(kBundleExtension) + ".objects";
    const json& objects = extension["objects"];
    if (!objects.is_array() || objects.empty()) throw Error(path, place, "is not a non-empty array");
    std::set<std::string> names;
    for (size_t k = 0; k < objects.size(); ++k) {
        std::string objectPlace = place + "[" + std::to_string(k) + "]";
        const json& record = objects[k];
        if (!record.is_object()) throw Error(path, objectPlace, "is not a JSON object");
        std::string name = stringMember(record, "name", path, objectPlace);
        std::string role = stringMember(record, "role", path, objectPlace);
        if (name.empty() || !names.insert(name).second) throw Error(path, objectPlace, "name is empty or not unique");
        if (!record.contains("mesh") || !record["mesh"].is_number_unsigned() || record["mesh"].get<uint64_t>() >= model.meshes.size())
            throw Error(path, objectPlace + ".mesh", "is not the index of a glTF mesh");
        TriMesh mesh = detail::readGltfMeshAt(model, record["mesh"].get<int>(), path);
        if (k == 0) {
            bundle.mesh = std::move(mesh);
            bundle.meshName = name;
            bundle.meshRole = role;
        } else {
            bundle.objects.push_back({name, role, std::move(mesh)});
        }
    }
}

static void readInstances(const json& extension, const std::string& path, Bundle& bundle) {
    const std::string place = std::string(kBundleExtension) + ".instances";
    const json& instances = extension["instances"];
    if (!instances.is_array()) throw Error(path, place, "is not an array");
    for (size_t i = 0; i < instances.size(); ++i) {
        std::string instancePlace = place + "[" + std::to_string(i) + "]";
        const json& record = instances[i];
        if (!record.is_object()) throw Error(path, instancePlace, "is not a JSON object");
        Instance instance;
        if (record.contains("name")) instance.name = stringMember(record, "name", path, instancePlace);
        if (!record.contains("object") || !record["object"].is_number_unsigned() || record["object"].get<uint64_t>() > bundle.objects.size())
            throw Error(path, instancePlace + ".object", "is not the index of an object");
        instance.object = record["object"].get<uint32_t>();
        if (record.contains("translation")) {
            const json& t = record["translation"];
            if (!t.is_array() || t.size() != 3) throw Error(path, instancePlace + ".translation", "is not three numbers");
            for (int a = 0; a < 3; ++a) {
                if (!t[a].is_number() || !std::isfinite(t[a].get<double>()))
                    throw Error(path, instancePlace + ".translation", "is not three finite numbers");
                instance.translation[a] = t[a].get<float>();
            }
        }
        bundle.instances.push_back(instance);
    }
}

static void readRecords(const json& extension, const tinygltf::Model& model, const std::string& path, Bundle& bundle,
                        detail::StreamedBuffer* streamed) {
    const std::string place = kBundleExtension;
    int version = extension["version"].get<int>();
    bundle.producer = objectMember(extension, "producer", path, place);
    bundle.inputs = objectMember(extension, "inputs", path, place);
    bundle.convention = objectMember(extension, "convention", path, place);
    if (version >= 2 && extension.contains("instances")) readInstances(extension, path, bundle);
    if (!extension.contains("layers")) return;
    if (!extension["layers"].is_array()) throw Error(path, place + ".layers", "is not an array");
    std::set<std::string> names;
    for (size_t i = 0; i < extension["layers"].size(); ++i) {
        std::string layerPlace = place + ".layers[" + std::to_string(i) + "]";
        bundle.layers.push_back(readLayer(extension["layers"][i], model, bundle, version, path, layerPlace, streamed));
        if (!names.insert(bundle.layers.back().name).second) throw Error(path, layerPlace, "duplicate layer name");
    }
}

// A scene (plain glTF, or a version 3 bundle with a `scene` record): the flattened mesh and the asset's records
// into `bundle`. A bundle's record must describe the receivers the node tree gives, row for row.
static std::shared_ptr<SceneAsset> readSceneAsset(const tinygltf::Model& model, const std::string& path, const json* record,
                                                  Bundle& bundle) {
    auto asset = std::make_shared<SceneAsset>();
    bundle.mesh = detail::readGltfScene(model, path, *asset);
    if (!record) return asset;
    const std::string place = std::string(kBundleExtension) + ".scene";
    if (!record->is_object() || !record->contains("receivers") || !(*record)["receivers"].is_array())
        throw Error(path, place, "is not an object with a receivers array");
    const json& receivers = (*record)["receivers"];
    if (receivers.size() != asset->receivers.size())
        throw Error(path, place + ".receivers", "lists " + std::to_string(receivers.size()) + " receivers, the node tree gives " +
                                                    std::to_string(asset->receivers.size()));
    for (size_t i = 0; i < receivers.size(); ++i) {
        const json& r = receivers[i];
        const SceneReceiver& walked = asset->receivers[i];
        auto is = [&](const char* key, int64_t value) {
            return r.is_object() && r.contains(key) && r[key].is_number_integer() && r[key].get<int64_t>() == value;
        };
        if (!is("node", walked.node) || !is("mesh", walked.mesh) || !is("primitive", walked.primitive) ||
            !is("first_row", walked.firstVertex) || !is("rows", walked.vertexCount))
            throw Error(path, place + ".receivers[" + std::to_string(i) + "]",
                        "does not match the node tree's receiver " + std::to_string(i) + " (node " + std::to_string(walked.node) +
                            ", mesh " + std::to_string(walked.mesh) + ", primitive " + std::to_string(walked.primitive) + ")");
    }
    return asset;
}

// A scene bundle's layers are views at the end of buffer 0, after everything of the asset (writeBundle appends
// them): dropping those views and truncating the buffer gives back the asset alone, so that rewriting a bundle
// never carries old layers along. A file laid out otherwise keeps its views (the bytes are then dead weight).
static void dropLayerViews(tinygltf::Model& model, const json& extension) {
    std::set<size_t> layerViews;
    for (const json& layer : extension.value("layers", json::array()))
        if (layer.is_object() && layer.contains("bufferView") && layer["bufferView"].is_number_unsigned())
            layerViews.insert(layer["bufferView"].get<size_t>());
    if (layerViews.empty() || model.buffers.size() != 1) return;
    size_t first = *layerViews.begin();
    if (*layerViews.rbegin() != model.bufferViews.size() - 1 || layerViews.size() != model.bufferViews.size() - first) return;
    size_t cut = model.bufferViews[first].byteOffset, assetEnd = 0;
    for (size_t v = 0; v < first; ++v)
        assetEnd = std::max<size_t>(assetEnd, model.bufferViews[v].byteOffset + model.bufferViews[v].byteLength);
    if (assetEnd > cut || cut > model.buffers[0].data.size()) return;
    model.bufferViews.resize(first);
    model.buffers[0].data.resize(cut);
}

Bundle readBundle(const std::string& path) {
    std::string jsonText;
    tinygltf::Model model = loadModel(path, jsonText);
    return detail::bundleFromModel(std::move(model), std::move(jsonText), path, nullptr);
}

Bundle detail::bundleFromModel(tinygltf::Model model, std::string jsonText, const std::string& path, StreamedBuffer* streamed) {
    // tinygltf drops an extension whose value is not an object; the original JSON still names it, and a file that
    // claims to be a bundle is read as one (and refused), never silently as a plain mesh.
    bool hasExtension = model.extensions.count(kBundleExtension) > 0 ||
                        json::parse(model.extensions_json_string, nullptr, false).contains(kBundleExtension);
    Bundle bundle;
    try {
        if (streamed && !hasExtension) throw Error(path, "", "is a plain glTF file, not a prt bundle");
        json extension = hasExtension ? verifiedExtension(model, path, streamed) : json();
        int version = hasExtension ? extension["version"].get<int>() : 0;
        // Plain glTF and version 3 scenes: the asset and its flattened mesh. Version 1: the scene's triangles,
        // merged. Version 2 (and 3 without a scene): each object from its own mesh.
        std::shared_ptr<SceneAsset> asset;
        if (hasExtension && version >= 3 && extension.contains("scene")) {
            json record = extension["scene"];
            asset = readSceneAsset(model, path, &record, bundle);
        } else if (!hasExtension) {
            asset = readSceneAsset(model, path, nullptr, bundle);
        } else if (version >= 2 && extension.contains("objects")) {
            readObjects(extension, model, path, bundle);
        } else {
            bundle.mesh = detail::readGltfMesh(model, path);
        }
        if (hasExtension) readRecords(extension, model, path, bundle, streamed);
        if (asset) {
            asset->sourceJson = std::move(jsonText);
            if (hasExtension) dropLayerViews(model, extension);
            asset->source = detail::selfContainedModel(std::move(model));
            bundle.asset = std::move(asset);
        }
    } catch (const json::exception& e) {
        throw Error(path, kBundleExtension, std::string("malformed extension JSON: ") + e.what());
    }
    return bundle;
}

Bundle sceneFromModel(tinygltf::Model model, const std::string& file) {
    Bundle bundle;
    std::shared_ptr<SceneAsset> asset = readSceneAsset(model, file, nullptr, bundle);
    asset->source = detail::selfContainedModel(std::move(model));
    bundle.asset = std::move(asset);
    return bundle;
}

const Layer* findLayer(const Bundle& bundle, const std::string& name) {
    for (const Layer& layer : bundle.layers)
        if (layer.name == name) return &layer;
    return nullptr;
}

std::string objectLayerName(const std::string& base, uint32_t object) {
    return object == 0 ? base : base + "." + std::to_string(object);
}

const Layer* findObjectLayer(const Bundle& bundle, const std::string& base, uint32_t object) {
    std::string scoped = objectLayerName(base, object);
    for (const Layer& layer : bundle.layers)
        if (layer.object == object && (layer.name == base || layer.name == scoped)) return &layer;
    return nullptr;
}

} // namespace prt
