// The stages a pipeline can run: each entry mirrors one `prt STAGE` command line (apps/cli/STAGE.cpp).
//
// Code versions: bump a stage's `version` in the same change that alters the bytes it writes for the same inputs
// and parameters (a new estimator, a fixed bug, a new field in its output). Every cached result of that stage,
// and through the content hashes everything downstream that actually changes, reruns on the next `prt run`.
// Changes that leave outputs identical (speed, logging, messages) keep the version.
#include "pipeline.h"

namespace prt {

namespace {

constexpr double kMaxSeed = 9007199254740992.0; // 2^53: bundles store integers in JSON doubles
constexpr int kMaxOrder = 32;                    // sh::kMaxOrder

const ParamSpec kAlbedo = {"albedo", ParamType::Color, 0.0, 1.0};
const ParamSpec kSeed = {"seed", ParamType::Integer, 0.0, kMaxSeed};
const ParamSpec kRotateY = {"rotate-y", ParamType::Number, -360.0, 360.0};
const ParamSpec kWindow = {"window", ParamType::String, 0.0, 0.0, {"none", "hann", "lanczos"}};

std::string transferParamsRefusal(const nlohmann::json& params) {
    bool interreflected = params.value("mode", std::string("shadowed")) == "interreflected";
    if (params.contains("bounces") && !interreflected) return "'bounces' only applies to mode = \"interreflected\"";
    return "";
}

std::string adaptParamsRefusal(const nlohmann::json& params) {
    if (params.contains("order") == params.contains("max-error"))
        return "give exactly one of 'order' (uniform truncation) and 'max-error' (adaptive order)";
    return "";
}

// Sharded interreflected transfer with bounces: the direct pass, then one pass per bounce (lib/transfer).
int transferPasses(const nlohmann::json& params) {
    bool interreflected = params.value("mode", std::string("shadowed")) == "interreflected";
    int64_t bounces = interreflected ? params.value("bounces", int64_t(2)) : 0; // prt transfer's default: 2
    return int(bounces) + 1;
}

std::string glossyShardRefusal(const nlohmann::json& params) {
    if (params.value("bounces", int64_t(0)) > 0)
        return "diffuse interreflection (bounces) gathers from every vertex, so it cannot be sharded (set bounces = 0, "
               "wire a transfer stage into the 'diffuse' input, or shards = 1)";
    return "";
}

StageSpec sceneStage() {
    StageSpec scene{"scene", 1, "procedural scene with a known answer"};
    scene.outputs = {{"mesh", FileKind::Mesh, "-o", "glb"}};
    scene.params = {{"name", ParamType::String, 0.0, 0.0,
                     {"sphere", "plane", "box-room", "cavity", "sphere-in-cavity", "two-spheres"}, true, true}};
    return scene;
}

// 2: glTF scenes and OBJ with MTL are kept as the asset (scene bundles, version 3)
StageSpec meshprepStage() {
    StageSpec meshprep{"meshprep", 2, "clean a mesh: weld, normals, decimation; keep a glTF or OBJ+MTL scene as the asset"};
    meshprep.inputs = {{"mesh", FileKind::Mesh, "", ""}};
    meshprep.outputs = {{"mesh", FileKind::Mesh, "-o", "glb"}, {"report", FileKind::Report, "--report", "json"}};
    meshprep.params = {{"weld-tolerance", ParamType::Number, 0.0, 1.0}, // of the bounding-box diagonal
                       {"weld-ignore-attributes", ParamType::Boolean},
                       {"recompute-normals", ParamType::Boolean},
                       {"decimate-to", ParamType::Integer, 1.0, 2147483647.0}, // triangles
                       {"scale", ParamType::Number, 1e-30, 1e30},
                       {"flatten", ParamType::Boolean}};
    return meshprep;
}

StageSpec envshStage() {
    StageSpec envsh{"envsh", 1, "project an environment map onto SH"};
    envsh.inputs = {{"env", FileKind::Env, "", ""}};
    envsh.outputs = {{"sh", FileKind::Sh, "-o", "json"}};
    envsh.params = {{"order", ParamType::Integer, 1.0, kMaxOrder}, kRotateY, kWindow};
    return envsh;
}

// 2: transfer_bounce layer; 3: one spawn rule (lib/raycast); 4: scenes (materials at hits, irradiance transfer)
StageSpec transferStage() {
    StageSpec transfer{"transfer", 5, "per-vertex SH transfer by ray casting"};
    transfer.inputs = {{"mesh", FileKind::Mesh, "", ""}};
    transfer.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    transfer.params = {{"mode", ParamType::String, 0.0, 0.0, {"unshadowed", "shadowed", "interreflected"}},
                       {"order", ParamType::Integer, 1.0, kMaxOrder},
                       {"samples", ParamType::Integer, 1.0, 65536.0},
                       {"bounces", ParamType::Integer, 0.0, 64.0},
                       kAlbedo,
                       kSeed};
    transfer.takesThreads = true;
    transfer.shardable = true;
    transfer.paramsRefusal = transferParamsRefusal;
    transfer.passes = transferPasses;
    return transfer;
}

// Adaptive order and compact storage of a transfer bundle (docs/adapt.md); one map at most as its prior, which
// `order` (uniform truncation) does without.
StageSpec adaptStage() {
    StageSpec adapt{"adapt", 1, "adaptive SH order and compact storage of a transfer bundle"};
    adapt.inputs = {{"bundle", FileKind::Bundle, "", ""}, {"env", FileKind::Env, "--env", "", true}};
    adapt.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    adapt.params = {{"order", ParamType::Integer, 1.0, kMaxOrder},
                    {"max-error", ParamType::Number, 1e-9, 1.0},
                    {"budget", ParamType::String, 0.0, 0.0, {"rms", "vertex"}},
                    {"prior", ParamType::String, 0.0, 0.0, {"maps", "worst"}},
                    {"format", ParamType::String, 0.0, 0.0, {"float", "half", "u16", "u8", "cpca"}},
                    {"scales", ParamType::String, 0.0, 0.0, {"per-vertex", "per-cluster"}},
                    {"clusters", ParamType::Integer, 1.0, 65536.0},
                    {"components", ParamType::Integer, 0.0, 65536.0},
                    {"max-step", ParamType::Integer, 1.0, kMaxOrder}};
    adapt.paramsRefusal = adaptParamsRefusal;
    return adapt;
}

// Shards are ranges of covered texels ("texel_range" layers). Gutter fill and seam stitching couple the whole
// atlas, so the merge is `prt bake ... --merge SHARD...`, which joins the rows and finishes as one bake does.
// 3: spawn rule, content-addressed textures; 4: texel_surface and texel_transfer_bounce layers (texel hybrid)
StageSpec bakeStage() {
    StageSpec bake{"bake", 5, "per-texel SH transfer into atlas textures"};
    bake.inputs = {{"mesh", FileKind::Mesh, "", ""}, {"high", FileKind::Mesh, "--high", "", true}};
    // The textures land next to the bundle (bundle.transfer.exr, ...), listed in its layers' params.files; `prt run`
    // copies them along with the bundle.
    bake.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    bake.params = {{"resolution", ParamType::Integer, 1.0, 16384.0},
                   {"order", ParamType::Integer, 1.0, kMaxOrder},
                   {"samples", ParamType::Integer, 1.0, 65536.0},
                   {"bounces", ParamType::Integer, 0.0, 64.0},
                   kAlbedo,
                   {"uv-set", ParamType::Integer, 0.0, 7.0},
                   {"format", ParamType::String, 0.0, 0.0, {"half", "float", "u8"}},
                   {"wrap", ParamType::String, 0.0, 0.0, {"none", "repeat"}},
                   {"allow-overlap", ParamType::Boolean},
                   {"generate-atlas", ParamType::Boolean},
                   {"dilate-only", ParamType::Boolean},
                   {"no-seam-stitch", ParamType::Boolean},
                   {"low-position", ParamType::Boolean},
                   {"cage", ParamType::Number, 1e-9, 0.999999},
                   {"max-miss", ParamType::Number, 0.0, 1.0},
                   {"padding", ParamType::Integer, 2.0, 1024.0},
                   kSeed};
    bake.takesThreads = true;
    bake.shardable = true;
    bake.mergeFlag = "--merge";
    return bake;
}

// Cone lights plus SH residual (prt-lights JSON). Lights files travel as FileKind::Sh: SH lighting in JSON,
// read only by the ports named "lights".
StageSpec envlightStage() {
    StageSpec envlight{"envlight", 1, "split an environment map into cone lights plus an SH residual"};
    envlight.inputs = {{"env", FileKind::Env, "", ""}};
    envlight.outputs = {{"lights", FileKind::Sh, "-o", "json"}};
    envlight.params = {{"order", ParamType::Integer, 1.0, kMaxOrder},
                       {"max-lights", ParamType::Integer, 0.0, 64.0},
                       {"min-lights", ParamType::Integer, 0.0, 64.0},
                       kRotateY,
                       {"elbow", ParamType::Number, 0.0, 0.999},
                       {"min-contrast", ParamType::Number, 0.0, 1e30},
                       {"icosphere-level", ParamType::Integer, 3.0, 8.0},
                       {"smoothing", ParamType::Number, 1e-3, 20.0},
                       {"min-radius", ParamType::Number, 1e-3, 89.0},
                       {"max-radius", ParamType::Number, 1e-3, 89.0},
                       {"detection-window", ParamType::String, 0.0, 0.0, {"none", "hann", "lanczos"}},
                       {"thesis-lights", ParamType::Boolean},
                       {"fixed-radius", ParamType::Number, 1e-3, 89.0}};
    return envlight;
}

// Glossy lobes per vertex and view plus the diffuse transfer (docs/glossy.md). Shards are vertex ranges joined by
// mergeShards; the diffuse part comes from `bounces` (unshardable above 0) or a wired transfer bundle.
StageSpec glossyStage() {
    StageSpec glossy{"glossy", 1, "glossy view-dependent transfer: spherical-Gaussian lobes per vertex and view"};
    glossy.inputs = {{"mesh", FileKind::Mesh, "", ""}, {"diffuse", FileKind::Bundle, "--diffuse", "", true}};
    glossy.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    glossy.params = {{"brdf", ParamType::String, 0.0, 0.0, {}, false, true}, // phong:EXPONENT,KS
                     kAlbedo,
                     {"lobes", ParamType::Integer, 1.0, 4.0},
                     {"solver", ParamType::String, 0.0, 0.0, {"pocl", "ceres"}},
                     {"bounces", ParamType::Integer, 0.0, 64.0},
                     {"order", ParamType::Integer, 1.0, kMaxOrder},
                     {"samples", ParamType::Integer, 1.0, 65536.0},
                     {"grid", ParamType::Integer, 2.0, 64.0},
                     {"beta", ParamType::Number, 0.0, 1e6},
                     {"gamma", ParamType::Number, 0.0, 1e6},
                     {"delta", ParamType::Number, 0.0, 1e6},
                     {"no-coherence", ParamType::Boolean},
                     {"iterations", ParamType::Integer, 1.0, 100000.0},
                     {"lobe-type", ParamType::String, 0.0, 0.0, {"float16", "float32"}},
                     {"indirect-glossy", ParamType::Boolean},
                     {"warm-start", ParamType::Boolean},
                     {"nested", ParamType::Boolean},
                     {"from-below", ParamType::Boolean},
                     {"overshoot", ParamType::Number, 1e-9, 1e6},
                     {"held-out-grid", ParamType::Integer, 0.0, 64.0}};
    glossy.takesThreads = true;
    glossy.shardable = true;
    glossy.shardRefusal = glossyShardRefusal;
    return glossy;
}

// 2: the decomposed lighting (lights input) keeps its negative residual instead of clamping it
// 3: scenes traced with their materials
StageSpec referenceStage() {
    StageSpec reference{"reference", 3, "ground-truth radiance by path tracing"};
    reference.inputs = {{"mesh", FileKind::Mesh, "", ""},
                        {"env", FileKind::Env, "--env", "", true},
                        {"lights", FileKind::Sh, "--lights", "", true}};
    reference.exactlyOneInput = {"env", "lights"};
    reference.outputs = {{"radiance", FileKind::Radiance, "-o", "npy"},
                         {"standard-error", FileKind::Radiance, "--stderr-out", "npy"}};
    reference.params = {{"bounces", ParamType::Integer, 0.0, 64.0},
                        {"samples", ParamType::Integer, 2.0, 16777216.0},
                        kAlbedo,
                        kSeed,
                        {"lights-width", ParamType::Integer, 4.0, 16384.0},
                        {"brdf", ParamType::String}, // phong:EXPONENT,KS: glossy ground truth toward `eye`
                        {"eye", ParamType::String}};
    reference.takesThreads = true;
    return reference;
}

// 2: a scene's irradiance transfer times its diffuse_albedo layer
StageSpec relightStage() {
    StageSpec relight{"relight", 2, "per-vertex radiance of a bundle under new lighting"};
    relight.inputs = {{"bundle", FileKind::Bundle, "", ""},
                      {"env", FileKind::Env, "--env", "", true},
                      {"sh", FileKind::Sh, "--sh", "", true},
                      {"lights", FileKind::Sh, "--lights", "", true}};
    relight.exactlyOneInput = {"env", "sh", "lights"};
    relight.alsoTogether = {{"env", "lights"}}; // a glossy bundle's lights path (docs/glossy.md) needs the map too
    relight.outputs = {{"radiance", FileKind::Radiance, "-o", "npy"}};
    // eye (and glossy-only) add a glossy bundle's lobes toward that point.
    relight.params = {kRotateY, kWindow, {"light-samples", ParamType::Integer, 0.0, 65536.0},
                      {"eye", ParamType::String}, {"glossy-only", ParamType::Boolean}};
    return relight;
}

StageSpec compareStage() {
    StageSpec compare{"compare", 1, "error metrics of a result against a reference"};
    compare.inputs = {{"result", FileKind::Radiance, "", ""}, {"reference", FileKind::Radiance, "", ""}};
    compare.outputs = {{"metrics", FileKind::Metrics, "-o", "json"}};
    return compare;
}

// FIV (docs/fiv.md) in two stages, so that a new environment reruns only the cheap reduction: the masks
// (`prt fiv-visibility`, sharded over grid rows and joined by `--merge`), then `prt fiv VISIBILITY --env`.
StageSpec fivVisibilityStage() {
    StageSpec fivVisibility{"fiv-visibility", 1, "FIV visibility masks of an occluder type (environment-independent)"};
    fivVisibility.inputs = {{"mesh", FileKind::Mesh, "", ""}};
    fivVisibility.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    fivVisibility.params = {{"grid", ParamType::String},
                            {"shells", ParamType::String},
                            {"spacing", ParamType::String, 0.0, 0.0, {"log", "linear"}},
                            {"cube", ParamType::Integer, 1.0, 256.0},
                            {"supersample", ParamType::Integer, 1.0, 8.0},
                            {"allow-open", ParamType::Boolean}};
    fivVisibility.takesThreads = true;
    fivVisibility.shardable = true;
    fivVisibility.mergeFlag = "--merge";
    return fivVisibility;
}

StageSpec fivStage() {
    StageSpec fiv{"fiv", 1, "FIV grid, DifMap and FIV(Env): the environment reduction of the masks"};
    fiv.inputs = {{"visibility", FileKind::Bundle, "", ""}, {"env", FileKind::Env, "--env", ""}};
    fiv.outputs = {{"bundle", FileKind::Bundle, "-o", "glb"}};
    fiv.params = {{"difmap", ParamType::Integer, 1.0, 256.0}, {"float32", ParamType::Boolean}};
    return fiv;
}

std::vector<StageSpec> makeCatalogue() {
    return {sceneStage(),     meshprepStage(), envshStage(),  transferStage(),  adaptStage(),
            bakeStage(),      envlightStage(), glossyStage(), referenceStage(), relightStage(),
            compareStage(),   fivVisibilityStage(), fivStage()};
}

} // namespace

const char* fileKindName(FileKind kind) {
    switch (kind) {
    case FileKind::Mesh: return "mesh";
    case FileKind::Bundle: return "bundle";
    case FileKind::Env: return "env";
    case FileKind::Sh: return "sh";
    case FileKind::Radiance: return "radiance";
    case FileKind::Metrics: return "metrics";
    case FileKind::Report: return "report";
    }
    return "?";
}

const std::vector<StageSpec>& stageCatalogue() {
    static const std::vector<StageSpec> catalogue = makeCatalogue();
    return catalogue;
}

const StageSpec* findStageSpec(const std::string& name) {
    for (const StageSpec& spec : stageCatalogue())
        if (spec.name == name) return &spec;
    return nullptr;
}

} // namespace prt
