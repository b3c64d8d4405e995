// prt relight --brdf phong:N,KS --eye X,Y,Z on a bundle with a "specular_visibility" layer: specular through SH
// triple products (lib/specular), plus the diffuse part from the bundle's transfer layer unless --glossy-only.
#include "cli.h"

#include "compare.h"
#include "core.h"
#include "runtime.h"
#include "specular.h"

#include <nlohmann/json.hpp>

#include <algorithm>

namespace prt::cli {

void addSpecularRelightOptions(CLI::App* command, SpecularRelightArgs& args) {
    CLI::Option* brdf = command->add_option("--brdf", args.brdf,
                                            "phong:EXPONENT,KS with --eye: specular through SH triple products from "
                                            "the bundle's specular_visibility layer (`prt specular`)");
    // What the specular relight does not do is refused rather than ignored (called after relight's own options).
    for (const char* other : {"--texels", "--image", "--camera", "--lights", "--sh", "--rotate-y", "--window",
                              "--irradiance", "--positions", "--visibility-out", "--visibility-turns"})
        if (CLI::Option* option = command->get_option_no_throw(other)) brdf->excludes(option);
    command->add_option("--light-order", args.lightOrder,
                        "With --brdf: SH bands of the lighting in the product (default: the visibility's order)")
        ->needs(brdf)
        ->check(CLI::NonNegativeNumber);
    command->add_option("--product-bands", args.productBands,
                        "With --brdf: most bands of the product kept (default: the visibility's order, as seed 004; "
                        "up to light order + visibility order - 1)")
        ->needs(brdf)
        ->check(CLI::NonNegativeNumber);
    command->add_option("--band-tolerance", args.bandTolerance,
                        "With --brdf: drop the product's bands whose Phong multiplier is below this share of band "
                        "0's (default 0.02; 0 keeps every band)")
        ->needs(brdf);
}

void runSpecularRelight(const SpecularRelightArgs& args, const std::string& bundlePath, const std::string& envPath,
                        const std::string& eyeText, const std::string& output, bool glossyOnly) {
    double start = nowSeconds();
    specular::Phong phong;
    parsePhongBrdf(args.brdf, phong.exponent, phong.ks);
    if (eyeText.empty())
        throw Error("", "--brdf", "needs --eye X,Y,Z: the specular part is view dependent", kExitUsage);
    if (envPath.empty()) throw Error("", "--brdf", "needs --env", kExitUsage);
    std::string extension = fileExtension(output);
    if (extension != "npy" && extension != "csv")
        throw Error(output, "-o", "output must end in .npy or .csv", kExitUsage);
    if (!(args.bandTolerance >= 0.0)) throw Error("", "--band-tolerance", "must be >= 0", kExitUsage);
    std::array<float, 3> eye = parsePoint(eyeText, "--eye");

    Bundle bundle = readBundle(bundlePath);
    specular::Visibility visibility = specular::readVisibility(bundle, bundlePath);
    const int lightOrder = args.lightOrder > 0 ? args.lightOrder : visibility.order;
    const int productBands = args.productBands > 0 ? args.productBands : visibility.order;
    if (lightOrder > sh::kMaxOrder)
        throw Error("", "--light-order", "above " + std::to_string(sh::kMaxOrder), kExitUsage);
    if (productBands > std::min(sh::kMaxOrder, lightOrder + visibility.order - 1))
        throw Error("", "--product-bands",
                    std::to_string(productBands) + " is more than the product of order " + std::to_string(lightOrder) +
                        " lighting and order " + std::to_string(visibility.order) + " visibility holds (" +
                        std::to_string(lightOrder + visibility.order - 1) + ")",
                    kExitUsage);
    const int bands = specular::adaptiveBands(phong.exponent, productBands, args.bandTolerance);
    // Lighting bands above bands + visibility order - 2 meet no kept output band (triangle rule of the Gaunt
    // tensor), so projecting them would change nothing: drop them, and the tensor stays small.
    const int lightOrderUsed = std::min(lightOrder, bands + visibility.order - 1);
    const TriMesh& mesh = bundle.mesh;
    std::vector<float> radiance(mesh.vertexCount() * 3, 0.0f);
    RelightModel diffuse;
    if (!glossyOnly) {
        if (!findLayer(bundle, "transfer"))
            throw Error(bundlePath, "layers",
                        "has no \"transfer\" layer for the diffuse part: give --glossy-only, or run `prt specular` "
                        "on a bundle from `prt transfer`");
        diffuse = relightModel(bundle, bundlePath);
    }
    EnvironmentMap environment = readEnvironmentMap(envPath);
    // One projection serves both parts: a lower order's coefficients are the first ones of a higher order's.
    double projectStart = nowSeconds();
    const int projectedOrder = std::max(lightOrderUsed, diffuse.order);
    std::vector<float> projected = environmentLighting(environment, projectedOrder, nullptr, sh::Window::None);
    auto truncated = [&](int order) {
        return fitLighting(projected.data(), projectedOrder * projectedOrder, order * order);
    };
    std::vector<float> lighting = truncated(lightOrderUsed);
    double tensorStart = nowSeconds();
    sh::TripleProduct tensor = sh::tripleProduct(std::max({lightOrderUsed, visibility.order, bands}));
    double productStart = nowSeconds();
    specular::LightProduct product =
        specular::lightProduct(tensor, lighting.data(), lightOrderUsed, visibility.order, bands, phong);
    double shadeStart = nowSeconds();
    std::vector<float> glossy(radiance.size());
    specular::glossyRadiance(mesh, visibility, product, eye.data(), glossy.data());
    double end = nowSeconds();
    if (!glossyOnly) relight(diffuse, truncated(diffuse.order).data(), 0, diffuse.vertexCount, radiance.data());
    for (size_t i = 0; i < radiance.size(); ++i) radiance[i] += glossy[i];

    char line[240];
    std::snprintf(line, sizeof line,
                  "relight: specular, %zu vertices, visibility order %d, lighting order %d, %d of %d product bands "
                  "(Phong n = %g): light product %.3f ms, shading %.3f ms",
                  mesh.vertexCount(), visibility.order, lightOrderUsed, bands, productBands, phong.exponent,
                  (shadeStart - productStart) * 1e3, (end - shadeStart) * 1e3);
    logInfo(line);
    writeVertexRadiance(output, radiance);
    logInfo("relight: wrote " + output);
    nlohmann::json record = {{"vertices", mesh.vertexCount()},          {"visibility_order", visibility.order},
                             {"light_order", lightOrderUsed},               {"product_bands", productBands},
                             {"bands", bands},                          {"exponent", phong.exponent},
                             {"project_seconds", tensorStart - projectStart},
                             {"tensor_seconds", productStart - tensorStart},
                             {"tensor_entries", tensor.value.size()},
                             {"product_seconds", shadeStart - productStart}, {"shade_seconds", end - shadeStart}};
    logEvent("specular_relight_stats", record.dump());

    StageCost cost;
    cost.stage = "relight";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace prt::cli
