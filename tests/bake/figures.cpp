// The bake's figures, measured in one run and printed as JSON (not a test: it takes minutes).
//   bake_figures FULL.glb LOW.glb ENV.exr [--resolution N] [--order L] [--samples S]
// FULL is the full-resolution mesh, LOW its decimation (both from `prt meshprep`), ENV an environment map.
//   - throughput: texels/s and rays/s of the bake against bare Embree over the same rays, and the per-vertex stage
//   - side by side at FULL's vertices: relative RMSE against the path-traced reference of per-vertex transfer on
//     FULL, per-vertex transfer on LOW, and texels baked on LOW with and without detail from FULL
//   - seams: relit radiance jump across LOW's atlas seams, texels (stitched or not) against per-vertex
//   - push-pull and one-ring dilation time on a 4096 x 4096 atlas, 27 and 75 channels
//   - storage per format
#include "bake.h"

#include "core.h"
#include "reference.h"
#include "runtime.h"
#include "transfer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

using namespace prt;
using nlohmann::json;

namespace {

// sqrt(sum (a - b)^2 / sum b^2) over the rows where `use` is set, all channels.
double relativeRmse(const std::vector<float>& a, const std::vector<float>& b, const std::vector<uint8_t>& use) {
    double error = 0.0, norm = 0.0;
    for (size_t i = 0; i < use.size(); ++i)
        if (use[i])
            for (int c = 0; c < 3; ++c) {
                error += std::pow(double(a[3 * i + c]) - b[3 * i + c], 2);
                norm += std::pow(double(b[3 * i + c]), 2);
            }
    return std::sqrt(error / norm);
}

std::vector<float> relightRows(const std::vector<float>& transfer, int order, const std::vector<float>& lighting) {
    size_t rows = transfer.size() / (3 * size_t(order) * order);
    std::vector<float> radiance(3 * rows);
    relight(transfer.data(), rows, order * order, lighting.data(), radiance.data());
    return radiance;
}

// Per-vertex values of `mesh` interpolated at (triangle, barycentric) points: [point][3].
std::vector<float> interpolate(const TriMesh& mesh, const std::vector<float>& perVertex,
                               const CageProjection& points) {
    std::vector<float> out(3 * points.hit.size(), 0.0f);
    for (size_t i = 0; i < points.hit.size(); ++i) {
        if (!points.hit[i]) continue;
        const uint32_t* corner = &mesh.indices[3 * size_t(points.triangle[i])];
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                out[3 * i + c] += points.barycentric[3 * i + k] * perVertex[3 * size_t(corner[k]) + c];
    }
    return out;
}

// The texel image looked up bilinearly at (triangle, barycentric) points of its mesh: [point][3].
std::vector<float> lookUp(const TriMesh& mesh, const std::vector<float>& image, int size,
                          const CageProjection& points) {
    std::vector<float> out(3 * points.hit.size(), 0.0f);
    for (size_t i = 0; i < points.hit.size(); ++i) {
        if (!points.hit[i]) continue;
        const uint32_t* corner = &mesh.indices[3 * size_t(points.triangle[i])];
        float u = 0.0f, v = 0.0f;
        for (int k = 0; k < 3; ++k) {
            u += points.barycentric[3 * i + k] * mesh.texcoords[2 * size_t(corner[k])];
            v += points.barycentric[3 * i + k] * mesh.texcoords[2 * size_t(corner[k]) + 1];
        }
        sampleBilinear(image.data(), size, size, 3, u, v, &out[3 * i]);
    }
    return out;
}

json bakeRecord(const BakeStats& stats) {
    return {{"texels", stats.texels},
            {"transfer_seconds", stats.transferSeconds},
            {"texels_per_second", stats.texels / stats.transferSeconds},
            {"rays", stats.rays},
            {"rays_per_second", stats.rays / stats.directSeconds},
            {"bare_embree_rays_per_second", stats.bareRaysPerSecond},
            {"ratio_to_bare", stats.rays / stats.directSeconds / stats.bareRaysPerSecond}};
}

// Push-pull against one-ring dilation on 4096^2: LOW's atlas rasterised at that size, 27 and 75 channels (orders
// 3 and 5), seeded with a pattern on the covered texels.
json fillFigures(const TriMesh& low, const std::string& lowPath) {
    const int size = 4096;
    RasterOptions raster;
    raster.width = raster.height = size;
    TexelSamples big = rasteriseAtlas(low, raster, lowPath);
    std::vector<uint8_t> covered = coverageMask(big);
    json fills = json::array();
    for (int fillChannels : {27, 75}) {
        std::vector<float> texels(size_t(size) * size * fillChannels, 0.0f);
        auto seed = [&] {
            std::fill(texels.begin(), texels.end(), 0.0f);
            for (size_t i = 0; i < big.texel.size(); ++i)
                for (int c = 0; c < fillChannels; ++c)
                    texels[size_t(big.texel[i]) * fillChannels + c] = float(i % 97) + c;
        };
        seed();
        double start = nowSeconds();
        pushPull(texels.data(), size, size, fillChannels, covered.data());
        double pushPullSeconds = nowSeconds() - start;
        seed();
        start = nowSeconds();
        dilateOneRing(texels.data(), size, size, fillChannels, covered.data());
        double dilateSeconds = nowSeconds() - start;
        fills.push_back({{"channels", fillChannels},
                         {"push_pull_seconds", pushPullSeconds},
                         {"dilate_one_ring_seconds", dilateSeconds}});
    }
    return {{"covered_fraction", double(big.texel.size()) / (double(size) * size)}, {"fills", fills}};
}

// Storage per texel format at order 3 and this resolution: `prt bake` into a temporary folder, the coefficient
// images', bundle's and normal map's bytes, against the uncompressed float and u8 sizes.
json storageFigures(const std::string& lowPath, const std::string& fullPath, int resolution, int samples) {
    std::string folder = (std::filesystem::temp_directory_path() / "prt_bake_figures").string();
    std::filesystem::create_directories(folder);
    json storage;
    for (TexelFormat format : {TexelFormat::Half, TexelFormat::Float, TexelFormat::U8}) {
        BakeOptions o;
        o.input = lowPath;
        o.high = fullPath;
        o.resolution = resolution;
        o.order = 3;
        o.samples = samples;
        o.format = format;
        o.output = folder + "/bunny_" + texelFormatName(format) + ".glb";
        runBake(o);
        uint64_t bytes = 0;
        for (const auto& entry : std::filesystem::directory_iterator(folder)) {
            std::string name = entry.path().filename().string();
            if (name.rfind("bunny_" + std::string(texelFormatName(format)) + ".transfer", 0) == 0)
                bytes += entry.file_size();
        }
        std::string normalMap = folder + "/" + readBundle(o.output).layers[1].params["uri"].get<std::string>();
        storage[texelFormatName(format)] = {{"coefficient_bytes", bytes},
                                            {"bundle_bytes", std::filesystem::file_size(o.output)},
                                            {"normal_map_bytes", std::filesystem::file_size(normalMap)}};
    }
    storage["uncompressed_float_bytes"] = uint64_t(resolution) * resolution * 27 * 4;
    storage["uncompressed_u8_bytes"] = uint64_t(resolution) * resolution * 27;
    std::filesystem::remove_all(folder);
    return storage;
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s FULL.glb LOW.glb ENV.exr [--resolution N] [--order L] [--samples S]\n",
                     argv[0]);
        return 2;
    }
    std::string fullPath = argv[1], lowPath = argv[2], envPath = argv[3];
    int resolution = 512, order = 5, samples = 1024;
    for (int i = 4; i + 1 < argc; i += 2) {
        std::string flag = argv[i];
        int value = std::stoi(argv[i + 1]);
        if (flag == "--resolution") resolution = value;
        if (flag == "--order") order = value;
        if (flag == "--samples") samples = value;
    }
    try {
        setLogOptions({true, false});
        json out;
        TriMesh full = readBundle(fullPath).mesh;
        EnvironmentMap env = readEnvironmentMap(envPath);
        std::vector<float> lighting = environmentLighting(env, order, nullptr, sh::Window::None);

        // ---- bakes of LOW: with detail from FULL (seams left raw here, stitched below) and without ----
        BakeOptions options;
        options.input = lowPath;
        options.resolution = resolution;
        options.order = order;
        options.samples = samples;
        options.yardstick = true;
        options.seamStitch = false;
        options.high = fullPath;
        BakedAtlas detailed = bakeAtlas(options);
        out["bake_with_high"] = bakeRecord(detailed.stats);
        options.high.clear();
        options.seamStitch = true;
        BakedAtlas plain = bakeAtlas(options);
        out["bake_low_only"] = bakeRecord(plain.stats);
        const TriMesh& low = detailed.mesh; // LOW with its atlas (generated when LOW has no UVs)
        std::vector<SeamEdge> seams = findSeams(low);
        std::vector<float> stitched = detailed.transfer;
        int channels = 3 * order * order;
        double stitchStart = nowSeconds();
        size_t stitchedTexels = stitchSeams(low, seams, resolution, resolution, stitched.data(), channels);
        double stitchSeconds = nowSeconds() - stitchStart;

        // ---- per-vertex transfer, FULL and LOW (LOW's atlas mesh: seam vertices split as the texels' are) ----
        TransferOptions vertexOptions;
        vertexOptions.order = order;
        vertexOptions.samples = samples;
        vertexOptions.progress = false;
        Transfer fullTransfer = computeTransfer(full, vertexOptions);
        RayThroughput fullBare = castBareOcclusionRays(full, vertexOptions);
        out["per_vertex_full"] = {{"vertices", full.vertexCount()},
                                  {"rays_per_second", fullTransfer.stats.rays / fullTransfer.stats.directSeconds},
                                  {"bare_embree_rays_per_second", fullBare.rays / fullBare.seconds}};
        Transfer lowTransfer = computeTransfer(low, vertexOptions);

        // ---- side by side at FULL's vertices, against the reference ----
        ReferenceOptions referenceOptions;
        referenceOptions.samples = 4096;
        ReferenceRadiance reference = referenceVertexRadiance(full, env, referenceOptions);
        double diagonal = 0.0;
        {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (size_t i = 0; i < full.positions.size(); ++i)
                lo[i % 3] = std::min(lo[i % 3], full.positions[i]), hi[i % 3] = std::max(hi[i % 3], full.positions[i]);
            for (int a = 0; a < 3; ++a) diagonal += double(hi[a] - lo[a]) * (hi[a] - lo[a]);
            diagonal = std::sqrt(diagonal);
        }
        // Where each FULL vertex lies on LOW: along its normal, within 2% of the diagonal.
        CageProjection onLow = projectOntoHigh(low, full.positions, full.normals, float(0.02 * diagonal));
        std::vector<uint8_t> use = onLow.hit;
        std::vector<float> fullRadiance = relightRows(fullTransfer.coefficients, order, lighting);
        std::vector<float> lowVertexRadiance = relightRows(lowTransfer.coefficients, order, lighting);
        std::vector<float> lowRadiance = interpolate(low, lowVertexRadiance, onLow);
        std::vector<float> detailedImage = relightRows(stitched, order, lighting);
        std::vector<float> rawImage = relightRows(detailed.transfer, order, lighting);
        std::vector<float> plainImage = relightRows(plain.transfer, order, lighting);
        std::vector<float> detailedRadiance = lookUp(low, detailedImage, resolution, onLow);
        std::vector<float> plainRadiance = lookUp(low, plainImage, resolution, onLow);
        // The reference's own noise on the same scale: its standard error as if it were an error.
        std::vector<float> referencePlusError = reference.radiance;
        for (size_t i = 0; i < referencePlusError.size(); ++i) referencePlusError[i] += reference.standardError[i];
        out["side_by_side"] = {
            {"points", "vertices of FULL (" + std::to_string(full.vertexCount()) + "), " +
                           std::to_string(onLow.misses) + " of them found no LOW surface and are left out"},
            {"env", std::filesystem::path(envPath).filename().string()},
            {"reference_paths_per_vertex", referenceOptions.samples},
            {"reference_relative_standard_error", relativeRmse(referencePlusError, reference.radiance, use)},
            {"relative_rmse",
             {{"per_vertex_full", relativeRmse(fullRadiance, reference.radiance, use)},
              {"per_vertex_low", relativeRmse(lowRadiance, reference.radiance, use)},
              {"texel_low", relativeRmse(plainRadiance, reference.radiance, use)},
              {"texel_low_high_detail", relativeRmse(detailedRadiance, reference.radiance, use)}}},
            {"full_triangles", full.triangleCount()},
            {"low_triangles", low.triangleCount()}};

        // ---- seams ----
        SeamJump vertexJump = vertexSeamJump(low, seams, lowVertexRadiance.data(), 8);
        SeamJump rawJump = texelSeamJump(low, seams, rawImage.data(), resolution, resolution, 8);
        SeamJump stitchedJump = texelSeamJump(low, seams, detailedImage.data(), resolution, resolution, 8);
        SeamJump plainJump = texelSeamJump(low, seams, plainImage.data(), resolution, resolution, 8);
        out["seams"] = {{"edges", seams.size()},
                        {"stitched_texels", stitchedTexels},
                        {"stitch_seconds", stitchSeconds},
                        {"relative_rms_jump",
                         {{"per_vertex_low", vertexJump.rms / vertexJump.meanRadiance},
                          {"texel_high_detail_unstitched", rawJump.rms / rawJump.meanRadiance},
                          {"texel_high_detail_stitched", stitchedJump.rms / stitchedJump.meanRadiance},
                          {"texel_low_only_stitched", plainJump.rms / plainJump.meanRadiance}}}};

        out["fill_4096"] = fillFigures(low, lowPath);
        out["storage_order3"] = storageFigures(lowPath, fullPath, resolution, samples);
        std::cout << out.dump(2) << std::endl;
    } catch (const Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return e.exitCode();
    }
    return 0;
}
