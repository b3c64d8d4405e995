// The materials, textures, samplers and images of a glTF scene (asset.h), each value checked after conversion.
#include "bundle_internal.h"

#include "core.h"

#include <cmath>
#include <set>

namespace prt::detail {
namespace {

// Extensions prt honours when a file requires them. Any other required extension is refused by name, since
// reading the file without it would bake something other than the asset.
const std::set<std::string> kHonouredExtensions = {
    "KHR_texture_transform", // base colour texture transforms (below)
    "KHR_mesh_quantization", // integer attributes, which the accessor reader converts
    "KHR_materials_emissive_strength", "KHR_materials_specular", "KHR_materials_ior", // ignored by diffuse transfer
};

std::string requiredExtensionAdvice(const std::string& name) {
    if (name == "KHR_draco_mesh_compression" || name == "EXT_meshopt_compression")
        return "; prt reads uncompressed geometry: decompress the file first (for example `gltf-transform copy` or "
               "`gltfpack -noq`)";
    if (name == "KHR_texture_basisu" || name == "EXT_texture_webp")
        return "; prt reads PNG and JPEG textures: convert the textures first";
    return "";
}

bool finiteIn(double value, double low, double high) { return std::isfinite(value) && value >= low && value <= high; }

// A tinygltf::Value that must be an array of `n` finite numbers.
bool readNumbers(const tinygltf::Value& value, size_t n, double* out) {
    if (!value.IsArray() || value.ArrayLen() != n) return false;
    for (size_t i = 0; i < n; ++i) {
        const tinygltf::Value& element = value.Get(int(i));
        if (!element.IsNumber()) return false;
        out[i] = element.GetNumberAsDouble();
        if (!std::isfinite(out[i])) return false;
    }
    return true;
}

// KHR_texture_transform of a texture reference: translation * rotation * scale, and its texCoord override.
void readTextureTransform(const tinygltf::ExtensionMap& extensions, const std::string& file, const std::string& place,
                          MaterialRecord& material) {
    auto found = extensions.find("KHR_texture_transform");
    if (found == extensions.end()) return;
    const std::string at = place + ".extensions.KHR_texture_transform";
    const tinygltf::Value& transform = found->second;
    if (!transform.IsObject()) throw Error(file, at, "is not a JSON object");
    double offset[2] = {0, 0}, scale[2] = {1, 1}, rotation = 0;
    if (transform.Has("offset") && !readNumbers(transform.Get("offset"), 2, offset))
        throw Error(file, at + ".offset", "is not two finite numbers");
    if (transform.Has("scale") && !readNumbers(transform.Get("scale"), 2, scale))
        throw Error(file, at + ".scale", "is not two finite numbers");
    if (transform.Has("rotation")) {
        const tinygltf::Value& r = transform.Get("rotation");
        if (!r.IsNumber() || !std::isfinite(r.GetNumberAsDouble())) throw Error(file, at + ".rotation", "is not a finite number");
        rotation = r.GetNumberAsDouble();
    }
    if (transform.Has("texCoord")) {
        const tinygltf::Value& t = transform.Get("texCoord");
        if (!t.IsInt() || t.GetNumberAsInt() < 0 || t.GetNumberAsInt() > 1)
            throw Error(file, at + ".texCoord", "must be 0 or 1 (prt reads TEXCOORD_0 and TEXCOORD_1)");
        material.texCoord = t.GetNumberAsInt();
    }
    double c = std::cos(rotation), s = std::sin(rotation);
    // [1 0 ox; 0 1 oy] [c s; -s c] [sx 0; 0 sy], the extension's matrix.
    material.uvTransform = {float(c * scale[0]), float(s * scale[1]), float(offset[0]),
                            float(-s * scale[0]), float(c * scale[1]), float(offset[1])};
}

MaterialRecord readMaterial(const tinygltf::Model& model, size_t index, const std::string& file) {
    const tinygltf::Material& source = model.materials[index];
    const std::string place = "materials[" + std::to_string(index) + "]";
    const tinygltf::PbrMetallicRoughness& pbr = source.pbrMetallicRoughness;
    MaterialRecord material;
    material.name = source.name;
    if (pbr.baseColorFactor.size() != 4) throw Error(file, place + ".pbrMetallicRoughness.baseColorFactor", "is not 4 numbers");
    for (int c = 0; c < 4; ++c) {
        if (!finiteIn(pbr.baseColorFactor[c], 0.0, 1.0))
            throw Error(file, place + ".pbrMetallicRoughness.baseColorFactor", "components must lie in [0, 1]");
        material.baseColorFactor[c] = float(pbr.baseColorFactor[c]);
    }
    if (!finiteIn(pbr.metallicFactor, 0.0, 1.0))
        throw Error(file, place + ".pbrMetallicRoughness.metallicFactor", "must lie in [0, 1]");
    material.metallic = float(pbr.metallicFactor);
    if (pbr.baseColorTexture.index >= 0) {
        const std::string at = place + ".pbrMetallicRoughness.baseColorTexture";
        if (size_t(pbr.baseColorTexture.index) >= model.textures.size())
            throw Error(file, at + ".index", "texture " + std::to_string(pbr.baseColorTexture.index) + " does not exist");
        if (pbr.baseColorTexture.texCoord < 0 || pbr.baseColorTexture.texCoord > 1)
            throw Error(file, at + ".texCoord", "must be 0 or 1 (prt reads TEXCOORD_0 and TEXCOORD_1)");
        material.baseColorTexture = pbr.baseColorTexture.index;
        material.texCoord = pbr.baseColorTexture.texCoord;
        readTextureTransform(pbr.baseColorTexture.extensions, file, at, material);
    }
    if (source.alphaMode == "OPAQUE") {
        material.alphaMode = AlphaMode::Opaque;
    } else if (source.alphaMode == "MASK") {
        material.alphaMode = AlphaMode::Mask;
    } else if (source.alphaMode == "BLEND") {
        material.alphaMode = AlphaMode::Blend;
    } else {
        throw Error(file, place + ".alphaMode", "'" + source.alphaMode.substr(0, 40) + "' is not OPAQUE, MASK or BLEND");
    }
    if (!finiteIn(source.alphaCutoff, 0.0, 1e30)) throw Error(file, place + ".alphaCutoff", "must be a finite number >= 0");
    material.alphaCutoff = float(source.alphaCutoff);
    material.doubleSided = source.doubleSided;
    return material;
}

bool isWrap(int mode) {
    return mode == TINYGLTF_TEXTURE_WRAP_REPEAT || mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE ||
           mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT;
}

bool isFilter(int filter, bool minifying) {
    if (filter == -1 || filter == TINYGLTF_TEXTURE_FILTER_NEAREST || filter == TINYGLTF_TEXTURE_FILTER_LINEAR) return true;
    return minifying && filter >= TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST &&
           filter <= TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
}

// The image's encoded bytes as loadModel keeps them (tinygltf::Image::image, as_is), and its type: the declared
// mimeType, else what the bytes start with.
ImageRecord readImage(const tinygltf::Model& model, size_t index) {
    const tinygltf::Image& image = model.images[index];
    ImageRecord record;
    record.name = image.name;
    record.bytes = image.image;
    // A self-contained model (selfContainedModel) keeps the bytes in the image's buffer view instead.
    if (record.bytes.empty() && image.bufferView >= 0 && size_t(image.bufferView) < model.bufferViews.size()) {
        const tinygltf::BufferView& view = model.bufferViews[size_t(image.bufferView)];
        if (view.buffer >= 0 && size_t(view.buffer) < model.buffers.size()) {
            const std::vector<unsigned char>& buffer = model.buffers[size_t(view.buffer)].data;
            if (view.byteOffset <= buffer.size() && view.byteLength <= buffer.size() - view.byteOffset)
                record.bytes.assign(buffer.begin() + std::ptrdiff_t(view.byteOffset),
                                    buffer.begin() + std::ptrdiff_t(view.byteOffset + view.byteLength));
        }
    }
    record.mimeType = image.mimeType;
    const std::vector<unsigned char>& b = record.bytes;
    if (record.mimeType.empty()) {
        if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') record.mimeType = "image/png";
        if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) record.mimeType = "image/jpeg";
    }
    return record;
}

} // namespace

void checkRequiredExtensions(const std::vector<std::string>& required, const std::string& file) {
    for (const std::string& name : required)
        if (!kHonouredExtensions.count(name) && name != kBundleExtension)
            throw Error(file, "extensionsRequired", "requires " + name.substr(0, 80) + ", which prt cannot honour" +
                                                         requiredExtensionAdvice(name));
}

void readMaterials(const tinygltf::Model& model, const std::string& file, SceneAsset& scene) {
    checkRequiredExtensions(model.extensionsRequired, file);
    for (size_t s = 0; s < model.samplers.size(); ++s) {
        const tinygltf::Sampler& sampler = model.samplers[s];
        const std::string place = "samplers[" + std::to_string(s) + "]";
        if (!isWrap(sampler.wrapS)) throw Error(file, place + ".wrapS", std::to_string(sampler.wrapS) + " is not a glTF wrap mode");
        if (!isWrap(sampler.wrapT)) throw Error(file, place + ".wrapT", std::to_string(sampler.wrapT) + " is not a glTF wrap mode");
        if (!isFilter(sampler.magFilter, false))
            throw Error(file, place + ".magFilter", std::to_string(sampler.magFilter) + " is not a glTF magnification filter");
        if (!isFilter(sampler.minFilter, true))
            throw Error(file, place + ".minFilter", std::to_string(sampler.minFilter) + " is not a glTF minification filter");
    }
    for (size_t i = 0; i < model.images.size(); ++i) {
        scene.images.push_back(readImage(model, i));
        // tinygltf only warns about an image file it cannot read; a bundle carries every image, so it must read.
        const std::string& uri = model.images[i].uri;
        if (scene.images.back().bytes.empty())
            throw Error(file, "images[" + std::to_string(i) + "]",
                        uri.empty() || uri.rfind("data:", 0) == 0
                            ? std::string("has no data")
                            : "cannot read '" + uri.substr(0, 120) +
                                  "': missing, or outside the glTF file's folder (prt follows URIs only into it)");
    }
    for (size_t t = 0; t < model.textures.size(); ++t) {
        const tinygltf::Texture& texture = model.textures[t];
        const std::string place = "textures[" + std::to_string(t) + "]";
        TextureRecord record;
        if (texture.source >= 0 && size_t(texture.source) >= model.images.size())
            throw Error(file, place + ".source", "image " + std::to_string(texture.source) + " does not exist");
        if (texture.sampler >= 0 && size_t(texture.sampler) >= model.samplers.size())
            throw Error(file, place + ".sampler", "sampler " + std::to_string(texture.sampler) + " does not exist");
        record.image = texture.source;
        if (texture.sampler >= 0) {
            const tinygltf::Sampler& sampler = model.samplers[size_t(texture.sampler)];
            record.wrapS = sampler.wrapS;
            record.wrapT = sampler.wrapT;
            record.magFilter = sampler.magFilter;
            record.minFilter = sampler.minFilter;
        }
        scene.textures.push_back(record);
    }
    for (size_t m = 0; m < model.materials.size(); ++m) {
        MaterialRecord material = readMaterial(model, m, file);
        if (material.baseColorTexture >= 0) {
            const TextureRecord& texture = scene.textures[size_t(material.baseColorTexture)];
            const std::string place = "materials[" + std::to_string(m) + "].pbrMetallicRoughness.baseColorTexture";
            if (texture.image < 0) throw Error(file, place, "its texture has no source image");
            const std::string& type = scene.images[size_t(texture.image)].mimeType;
            if (type != "image/png" && type != "image/jpeg")
                throw Error(file, "images[" + std::to_string(texture.image) + "]",
                            "is not PNG or JPEG ('" + type.substr(0, 40) + "'); prt reads PNG and JPEG textures");
        }
        scene.materials.push_back(material);
    }
    MaterialRecord fallback; // a primitive without material: white, not metallic (prt's diffuse default)
    fallback.name = "prt_default";
    scene.materials.push_back(fallback);
}

} // namespace prt::detail
