// Base colour textures decoded through OpenImageIO from the bytes a scene asset keeps, sizes bounded first.
#include "material.h"

#include "core.h"
#include "image_library.h"

#include <algorithm>
#include <cmath>

namespace prt {

float srgbToLinear(float encoded) {
    return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

namespace {

SurfaceImage decodeImage(const ImageRecord& record, const std::string& file, const std::string& place) {
    auto refuse = [&](const std::string& problem) { throw Error(file, place, problem, kExitInput); };
    if (record.bytes.empty()) refuse("has no data");
    // OpenImageIO picks its reader by the name's extension, then reads the bytes through the proxy.
    const char* name = record.mimeType == "image/png" ? "texture.png" : "texture.jpg";
    std::string error;
    const OpenedImage spec = openImageMemory(name, record.bytes.data(), record.bytes.size(), error);
    if (!spec.handle) refuse("is not a readable " + record.mimeType + " image (" + error.substr(0, 200) + ")");
    if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0 || spec.channels > 4)
        refuse("has " + std::to_string(spec.width) + " x " + std::to_string(spec.height) + " texels of " +
               std::to_string(spec.channels) + " channels; prt reads 1 to 4 channels");
    if (spec.width > kMaxTextureSide || spec.height > kMaxTextureSide ||
        uint64_t(spec.width) * uint64_t(spec.height) > kMaxTextureTexels)
        refuse("claims " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
               " texels, more than prt decodes (" + std::to_string(kMaxTextureSide) + " per side, " +
               std::to_string(kMaxTextureTexels) + " in all)");
    const int channels = spec.channels;
    checkedProduct({uint64_t(spec.width), uint64_t(spec.height), 4}, "texel values", file, place);
    std::vector<float> pixels(size_t(spec.width) * spec.height * channels);
    if (!readOpenedPixels(spec, channels, pixels.data(), error))
        refuse("cannot decode its texels (" + error.substr(0, 200) + ")");
    SurfaceImage image;
    image.width = spec.width;
    image.height = spec.height;
    const size_t count = size_t(spec.width) * spec.height;
    image.rgba.resize(count * 4);
    const bool alpha = channels == 2 || channels == 4;
    // glTF colours are not premultiplied, but OpenImageIO associates a PNG's alpha with its colours on reading
    // (unless the file says it is unassociated): divide it out again. Where alpha is 0 the colour is lost, and unused.
    const bool associated = alpha && !spec.unassociatedAlpha;
    for (size_t p = 0; p < count; ++p) {
        const float* in = &pixels[p * channels];
        float* out = &image.rgba[p * 4];
        const float a = alpha ? in[channels - 1] : 1.0f, scale = associated && a > 0.0f ? 1.0f / a : 1.0f;
        for (int c = 0; c < 3; ++c) out[c] = srgbToLinear(std::clamp(in[channels >= 3 ? c : 0] * scale, 0.0f, 1.0f));
        out[3] = alpha ? std::clamp(in[channels - 1], 0.0f, 1.0f) : 1.0f;
    }
    return image;
}

} // namespace

Surface decodeSurface(const Bundle& bundle, const std::string& file) {
    if (!bundle.asset) throw Error(file, "", "is not a scene (no glTF asset)", kExitFailure);
    Surface surface;
    surface.asset = bundle.asset;
    surface.mesh = &bundle.mesh;
    const SceneAsset& asset = *bundle.asset;
    surface.images.resize(asset.images.size());
    for (const MaterialRecord& material : asset.materials) {
        surface.cutouts = surface.cutouts || material.alphaMode != AlphaMode::Opaque;
        if (material.baseColorTexture < 0) continue;
        int image = asset.textures[size_t(material.baseColorTexture)].image;
        if (surface.images[size_t(image)].width == 0)
            surface.images[size_t(image)] =
                decodeImage(asset.images[size_t(image)], file, "images[" + std::to_string(image) + "]");
    }
    return surface;
}

} // namespace prt
