// The material rules of material.h at surface points and vertices.
#include "material.h"

#include <algorithm>
#include <cmath>

namespace prt {
namespace {

// Texel index along one axis for glTF's wrap mode (asset.h's enum values).
int wrapTexel(int i, int size, int mode) {
    if (mode == 33071) return std::clamp(i, 0, size - 1); // CLAMP_TO_EDGE
    if (mode == 33648) {                                  // MIRRORED_REPEAT
        int period = 2 * size;
        int k = ((i % period) + period) % period;
        return k < size ? k : period - 1 - k;
    }
    return ((i % size) + size) % size; // REPEAT
}

// Texture coordinates far outside [0, 1] lose float precision; wrapping happens on integers after this.
float finiteCoordinate(float x) { return std::isfinite(x) ? std::clamp(x, -1e6f, 1e6f) : 0.0f; }

// The point's vertex attribute `values` ([V][width]) interpolated with the barycentrics.
template <int width>
std::array<float, width> interpolate(const std::vector<float>& values, const uint32_t* corner, float b1, float b2) {
    std::array<float, width> out{};
    const float b0 = 1.0f - b1 - b2;
    for (int c = 0; c < width; ++c)
        out[c] = b0 * values[width * size_t(corner[0]) + c] + b1 * values[width * size_t(corner[1]) + c] +
                 b2 * values[width * size_t(corner[2]) + c];
    return out;
}

// Base colour of `material` at texcoords (per set) and COLOR_0.
std::array<float, 4> baseColor(const Surface& surface, const MaterialRecord& material, const float uv[2][2],
                               const float color[4]) {
    std::array<float, 4> out = material.baseColorFactor;
    if (material.baseColorTexture >= 0) {
        const TextureRecord& texture = surface.asset->textures[size_t(material.baseColorTexture)];
        const float* st = uv[material.texCoord];
        const std::array<float, 6>& m = material.uvTransform;
        float u = m[0] * st[0] + m[1] * st[1] + m[2], v = m[3] * st[0] + m[4] * st[1] + m[5];
        std::array<float, 4> texel = sampleTexture(surface.images[size_t(texture.image)], texture, u, v);
        for (int c = 0; c < 4; ++c) out[c] *= texel[c];
    }
    for (int c = 0; c < 4; ++c) out[c] *= color[c];
    return out;
}

} // namespace

std::array<float, 4> baseColorAt(const Surface& surface, size_t triangle, float b1, float b2) {
    const SceneAsset& asset = *surface.asset;
    const uint32_t* corner = &surface.mesh->indices[3 * triangle];
    float uv[2][2] = {{0, 0}, {0, 0}};
    for (int set = 0; set < 2; ++set)
        if (!asset.texcoords[set].empty()) {
            std::array<float, 2> st = interpolate<2>(asset.texcoords[set], corner, b1, b2);
            uv[set][0] = st[0];
            uv[set][1] = st[1];
        }
    float color[4] = {1, 1, 1, 1};
    if (!asset.colors.empty()) {
        std::array<float, 4> c = interpolate<4>(asset.colors, corner, b1, b2);
        std::copy(c.begin(), c.end(), color);
    }
    return baseColor(surface, asset.triangleMaterial(triangle), uv, color);
}

std::array<float, 4> sampleTexture(const SurfaceImage& image, const TextureRecord& texture, float u, float v) {
    if (image.width <= 0 || image.height <= 0) return {1, 1, 1, 1};
    const float x = finiteCoordinate(u) * float(image.width) - 0.5f, y = finiteCoordinate(v) * float(image.height) - 0.5f;
    auto texel = [&](int i, int j) {
        const float* p = &image.rgba[4 * (size_t(wrapTexel(j, image.height, texture.wrapT)) * image.width +
                                          size_t(wrapTexel(i, image.width, texture.wrapS)))];
        return std::array<float, 4>{p[0], p[1], p[2], p[3]};
    };
    if (texture.magFilter == 9728) // NEAREST
        return texel(int(std::floor(x + 0.5f)), int(std::floor(y + 0.5f)));
    const int i = int(std::floor(x)), j = int(std::floor(y));
    const float fx = x - float(i), fy = y - float(j);
    std::array<float, 4> a = texel(i, j), b = texel(i + 1, j), c = texel(i, j + 1), d = texel(i + 1, j + 1), out{};
    for (int k = 0; k < 4; ++k)
        out[k] = (1 - fy) * ((1 - fx) * a[k] + fx * b[k]) + fy * ((1 - fx) * c[k] + fx * d[k]);
    return out;
}

std::array<float, 3> diffuseAlbedoAt(const Surface& surface, size_t triangle, float b1, float b2) {
    std::array<float, 4> base = baseColorAt(surface, triangle, b1, b2);
    const float dielectric = 1.0f - surface.asset->triangleMaterial(triangle).metallic;
    return {std::clamp(base[0] * dielectric, 0.0f, 1.0f), std::clamp(base[1] * dielectric, 0.0f, 1.0f),
            std::clamp(base[2] * dielectric, 0.0f, 1.0f)};
}

bool presentAt(const Surface& surface, size_t triangle, float b1, float b2) {
    const MaterialRecord& material = surface.asset->triangleMaterial(triangle);
    if (material.alphaMode == AlphaMode::Opaque) return true;
    return baseColorAt(surface, triangle, b1, b2)[3] >= material.alphaCutoff;
}

std::vector<float> vertexDiffuseAlbedo(const Surface& surface) {
    const SceneAsset& asset = *surface.asset;
    std::vector<float> albedo(3 * surface.mesh->vertexCount());
    for (const SceneReceiver& receiver : asset.receivers) {
        const MaterialRecord& material = asset.materials[size_t(receiver.material)];
        for (uint32_t v = receiver.firstVertex; v < receiver.firstVertex + receiver.vertexCount; ++v) {
            float uv[2][2] = {{0, 0}, {0, 0}};
            for (int set = 0; set < 2; ++set)
                if (!asset.texcoords[set].empty()) {
                    uv[set][0] = asset.texcoords[set][2 * size_t(v)];
                    uv[set][1] = asset.texcoords[set][2 * size_t(v) + 1];
                }
            float color[4] = {1, 1, 1, 1};
            if (!asset.colors.empty()) std::copy_n(&asset.colors[4 * size_t(v)], 4, color);
            std::array<float, 4> base = baseColor(surface, material, uv, color);
            for (int c = 0; c < 3; ++c) albedo[3 * size_t(v) + c] = std::clamp(base[c] * (1.0f - material.metallic), 0.0f, 1.0f);
        }
    }
    return albedo;
}

} // namespace prt
