// prt render: primary rays through the shared pinhole camera, relit radiance interpolated at each hit.
#include "render.h"

#include "compare.h"
#include "core.h"
#include "material.h"
#include "runtime.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace prt {

namespace {

// What a primary ray found: the triangle and the barycentrics of its vertices 1 and 2 (Embree's u, v).
struct PrimaryHit {
    enum Kind { Miss, Front, Back } kind = Miss;
    uint32_t triangle = 0;
    float u = 0, v = 0;
};

// Casts one ray per pixel (rows in parallel; each pixel is independent, so the image does not depend on the
// thread count) and lets `shade` colour every front-face hit.
RenderedImage castPrimaryRays(const TriMesh& mesh, const PinholeCamera& camera,
                              const std::function<void(const PrimaryHit&, float*)>& shade, const Surface* surface = nullptr) {
    const PinholeRays rays = pinholeRays(camera);
    EmbreeScene embree(mesh, surface);
    RenderedImage result;
    result.radiance.width = camera.width;
    result.radiance.height = camera.height;
    const size_t pixels = size_t(camera.width) * camera.height;
    result.radiance.rgb.assign(pixels * 3, 0.0f);
    result.coverage.assign(pixels, 0.0f);
    Progress progress("render", uint64_t(camera.height));
    tbb::parallel_for(tbb::blocked_range<int>(0, camera.height), [&](const tbb::blocked_range<int>& rowRange) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (int y = rowRange.begin(); y != rowRange.end(); ++y) {
            for (int x = 0; x < camera.width; ++x) {
                size_t pixel = size_t(y) * camera.width + x;
                float d[3];
                pinholeRayDirection(rays, pixel, d);
                RTCRayHit rayHit{};
                rayHit.ray.org_x = camera.eye[0], rayHit.ray.org_y = camera.eye[1], rayHit.ray.org_z = camera.eye[2];
                rayHit.ray.dir_x = d[0], rayHit.ray.dir_y = d[1], rayHit.ray.dir_z = d[2];
                rayHit.ray.tnear = 0.0f;
                rayHit.ray.tfar = INFINITY;
                rayHit.ray.mask = 0xFFFFFFFFu;
                rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(embree.scene, &context, &rayHit);
                if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
                result.coverage[pixel] = 1.0f;
                PrimaryHit hit;
                hit.triangle = embree.flatTriangle(rayHit.hit);
                hit.u = rayHit.hit.u;
                hit.v = rayHit.hit.v;
                // Counter-clockwise fronts (docs/bundle.md): the face normal is (p1 - p0) x (p2 - p0).
                float n[3];
                triangleNormal(mesh, hit.triangle, n);
                if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0f) continue; // a back face stays black
                hit.kind = PrimaryHit::Front;
                shade(hit, &result.radiance.rgb[pixel * 3]);
            }
            progress.add(1);
        }
    });
    throwIfEmbreeFailed(embree.device, "render");
    progress.finish();
    result.rays = pixels;
    return result;
}

} // namespace

// A scene bake's layer "lightmap_uv": [3 T][2] uv per triangle corner (docs/bundle.md "Scene bakes"), checked.
std::vector<float> lightmapCorners(const Bundle& bundle, const std::string& source) {
    const Layer* layer = findLayer(bundle, "lightmap_uv");
    if (!layer)
        throw Error(source, "PRT_bundle", "a scene's texels need the layer \"lightmap_uv\": bake the scene again");
    if (layer->domain != "corner" || layer->componentType != "float32" ||
        layer->shape != std::vector<uint64_t>{uint64_t(bundle.mesh.indices.size()), 2} ||
        layer->data.size() != bundle.mesh.indices.size() * 2)
        throw Error(source, "layer \"lightmap_uv\"", "is not a float32 corner layer of shape [" +
                                                         std::to_string(bundle.mesh.indices.size()) + ", 2]");
    for (float value : layer->data)
        if (!std::isfinite(value)) throw Error(source, "layer \"lightmap_uv\"", "holds a value that is not finite");
    return layer->data;
}

RenderedImage renderVertexRadiance(const TriMesh& mesh, const std::vector<float>& radiance, const PinholeCamera& camera,
                                   const Surface* surface) {
    if (radiance.size() != mesh.vertexCount() * 3)
        throw Error("", "render", std::to_string(radiance.size() / 3) + " radiance rows for " +
                                      std::to_string(mesh.vertexCount()) + " vertices");
    return castPrimaryRays(
        mesh, camera,
        [&](const PrimaryHit& hit, float* out) {
            const uint32_t* corner = &mesh.indices[size_t(hit.triangle) * 3];
            float w = 1.0f - hit.u - hit.v;
            for (int c = 0; c < 3; ++c)
                out[c] = w * radiance[corner[0] * 3 + c] + hit.u * radiance[corner[1] * 3 + c] +
                         hit.v * radiance[corner[2] * 3 + c];
            if (!surface) return;
            std::array<float, 3> albedo = diffuseAlbedoAt(*surface, hit.triangle, hit.u, hit.v);
            for (int c = 0; c < 3; ++c) out[c] *= albedo[c];
        },
        surface);
}

RenderedImage renderGlossyRadiance(const TriMesh& mesh, const std::vector<float>& diffuse, const GlossyModel& glossy,
                                   const EnvironmentMap& environment, const std::string& envSource,
                                   const PinholeCamera& camera, bool glossyOnly, const GlossyConeLights* lights,
                                   const double* rotation, const PrefilteredEnvironment* prefiltered) {
    if (!glossyOnly && diffuse.size() != mesh.vertexCount() * 3)
        throw Error("", "render", std::to_string(diffuse.size() / 3) + " radiance rows for " +
                                      std::to_string(mesh.vertexCount()) + " vertices");
    if (glossy.vertexCount != mesh.vertexCount())
        throw Error("", "render", "the glossy lobes have " + std::to_string(glossy.vertexCount) + " vertices, the mesh " +
                                      std::to_string(mesh.vertexCount()));
    if (lights) checkGlossyConeLights(glossy, *lights, "render");
    if (environment.layout != EnvLayout::Equirectangular)
        throw Error(envSource, "--env", "the glossy runtime needs an equirectangular (2:1) map");
    PrefilteredEnvironment env = prefiltered ? *prefiltered : glossyRenderEnvironment(glossy, environment, envSource);
    if (rotation) std::copy_n(rotation, 9, env.rotation);
    return castPrimaryRays(mesh, camera, [&](const PrimaryHit& hit, float* out) {
        const uint32_t* corner = &mesh.indices[size_t(hit.triangle) * 3];
        const float w[3] = {1.0f - hit.u - hit.v, hit.u, hit.v};
        float p[3] = {0, 0, 0}, d[3];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) p[a] += w[k] * mesh.positions[size_t(corner[k]) * 3 + a];
        for (int a = 0; a < 3; ++a) d[a] = camera.eye[a] - p[a];
        const float length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int a = 0; a < 3; ++a) d[a] /= length; // the pixel's view direction, shared by the three corners
        for (int a = 0; a < 3; ++a) out[a] = 0.0f;
        for (int k = 0; k < 3; ++k) {
            if (!glossyOnly)
                for (int a = 0; a < 3; ++a) out[a] += w[k] * diffuse[size_t(corner[k]) * 3 + a];
            if (!(length > 0.0f)) continue;
            float lit[3];
            glossyRadianceToward(glossy, env, corner[k], d, lit);
            for (int a = 0; a < 3; ++a) out[a] += w[k] * lit[a];
            if (!lights) continue;
            glossyConeLightsToward(glossy, *lights, corner[k], d, lit);
            for (int a = 0; a < 3; ++a) out[a] += w[k] * lit[a];
        }
    });
}

RenderedImage renderTexelRadiance(const TriMesh& mesh, const Image& atlas, const PinholeCamera& camera,
                                  const float* cornerUv, const Surface* surface) {
    if (!cornerUv && mesh.texcoords.size() != mesh.vertexCount() * 2)
        throw Error("", "render", "the mesh has no TEXCOORD_0 for its texels (prt bake adds an atlas)");
    if (atlas.width <= 0 || atlas.height <= 0 || atlas.rgb.size() != size_t(atlas.width) * atlas.height * 3)
        throw Error("", "render", "the relit atlas has no texels or a wrong size");
    return castPrimaryRays(
        mesh, camera,
        [&](const PrimaryHit& hit, float* out) {
            const uint32_t* corner = &mesh.indices[size_t(hit.triangle) * 3];
            auto uvOf = [&](int k, int a) {
                return cornerUv ? cornerUv[(size_t(hit.triangle) * 3 + k) * 2 + a] : mesh.texcoords[corner[k] * 2 + a];
            };
            float w = 1.0f - hit.u - hit.v;
            float uv[2];
            for (int a = 0; a < 2; ++a) uv[a] = w * uvOf(0, a) + hit.u * uvOf(1, a) + hit.v * uvOf(2, a);
            // The nearest texel: texel (x, y) covers u in [x, x + 1) / width, v in [y, y + 1) / height.
            int x = std::clamp(int(std::floor(uv[0] * float(atlas.width))), 0, atlas.width - 1);
            int y = std::clamp(int(std::floor(uv[1] * float(atlas.height))), 0, atlas.height - 1);
            const float* texel = &atlas.rgb[(size_t(y) * atlas.width + x) * 3];
            std::copy(texel, texel + 3, out);
            if (!surface) return;
            std::array<float, 3> albedo = diffuseAlbedoAt(*surface, hit.triangle, hit.u, hit.v);
            for (int c = 0; c < 3; ++c) out[c] *= albedo[c];
        },
        surface);
}

void writeRenderedExr(const std::string& path, const Image& image, const std::vector<float>& coverage) {
    const size_t pixels = size_t(image.width) * image.height;
    std::vector<float> rgba(pixels * 4);
    for (size_t p = 0; p < pixels; ++p) {
        std::copy(&image.rgb[p * 3], &image.rgb[p * 3] + 3, &rgba[p * 4]);
        rgba[p * 4 + 3] = coverage.empty() ? 1.0f : coverage[p];
    }
    writeImagePixels(path, image.width, image.height, {"R", "G", "B", "A"}, rgba.data(), PixelStorage::Float);
}

void writeRenderedPicture(const std::string& path, const RenderedImage& image, float exposure) {
    std::string extension = fileExtension(path);
    if (extension == "exr") {
        writeRenderedExr(path, image.radiance, image.coverage);
    } else if (extension == "png") {
        Picture picture = tonemappedPicture(image.radiance.rgb.data(), image.radiance.width, image.radiance.height,
                                            exposure);
        writeImagePixels(path, picture.width, picture.height, {"R", "G", "B"}, picture.rgb.data());
    } else {
        throw Error(path, "-o", "the image must end in .exr (linear) or .png (tone mapped)", kExitUsage);
    }
}

} // namespace prt
