// Shared by the pipeline tests: temporary folders, small inputs made in code, and reading run reports.
#pragma once

#include "build_info.h"
#include "core.h"
#include "image.h"
#include "pipeline.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

namespace prt::test {

inline const std::string kPrt = PRT_BINARY_DIR "/prt";

// A fresh folder, removed with everything in it when the object goes.
struct TempDir {
    std::string path;
    TempDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "prt-pipeline-XXXXXX").string();
        path = mkdtemp(pattern.data());
    }
    ~TempDir() {
        std::error_code error;
        std::filesystem::remove_all(path, error);
    }
    std::string operator/(const std::string& name) const { return path + "/" + name; }
};

// Runs a shell command with stdout and stderr captured; returns its exit status.
inline int shell(const std::string& command, std::string* output = nullptr) {
    std::FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    std::string text;
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) text.append(buffer, got);
    int status = pclose(pipe);
    if (output) *output = text;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// An OBJ of two small spheres side by side, which shadow each other, without normals (meshprep computes them).
inline void writeTwoSpheresObj(const std::string& path) {
    TriMesh mesh = makeTwoSpheres(6, 12);
    std::ofstream out(path);
    char line[128];
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        std::snprintf(line, sizeof(line), "v %.6f %.6f %.6f\n", mesh.positions[3 * v], mesh.positions[3 * v + 1],
                      mesh.positions[3 * v + 2]);
        out << line;
    }
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        out << "f " << mesh.indices[3 * t] + 1 << " " << mesh.indices[3 * t + 1] + 1 << " " << mesh.indices[3 * t + 2] + 1 << "\n";
}

// A small equirectangular sky: brightness rising toward the zenith, warmer toward +X.
inline void writeSkyExr(const std::string& path, float brightness) {
    Image sky;
    sky.width = 32;
    sky.height = 16;
    for (int y = 0; y < sky.height; ++y)
        for (int x = 0; x < sky.width; ++x) {
            float up = 1.0f - (y + 0.5f) / sky.height, side = (x + 0.5f) / sky.width;
            sky.rgb.insert(sky.rgb.end(), {brightness * (0.2f + up + 0.3f * side), brightness * (0.2f + up),
                                           brightness * (0.3f + up)});
        }
    writeImage(path, sky);
}

inline void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

inline std::string replaceAll(const std::string& text, const std::string& from, const std::string& to) {
    std::string result;
    size_t start = 0;
    for (size_t at; (at = text.find(from, start)) != std::string::npos; start = at + from.size())
        result.append(text, start, at - start).append(to);
    return result.append(text, start);
}

// A pipeline's text with its folder placeholder "@DIR@" filled in.
inline std::string withDir(const std::string& text, const std::string& dir) { return replaceAll(text, "@DIR@", dir); }

// The pipeline most tests run: the two-spheres scene, shadowed transfer with `samples` directions in `shards`
// shards, relit under DIR/sky.exr (writeSkyExr), bundle and radiance written into the folder `out`.
inline std::string twoSpheresPipeline(const std::string& dir, int samples, int shards, const std::string& out) {
    std::string text = R"(
[inputs]
sky = { env = "@DIR@/sky.exr" }

[stages.ball]
run = "scene"
name = "two-spheres"

[stages.transfer]
run = "transfer"
inputs = { mesh = "ball" }
mode = "shadowed"
samples = @SAMPLES@
shards = @SHARDS@

[stages.relight]
run = "relight"
inputs = { bundle = "transfer", env = "sky" }

[outputs]
bundle = { from = "transfer", path = "@OUT@/bundle.glb" }
radiance = { from = "relight", path = "@OUT@/radiance.npy" }
)";
    text = replaceAll(replaceAll(text, "@SAMPLES@", std::to_string(samples)), "@SHARDS@", std::to_string(shards));
    return withDir(replaceAll(text, "@OUT@", out), dir);
}

// The same with interreflected transfer (`bounces` bounces; -1 leaves the stage's default, 2).
inline std::string interreflectedPipeline(const std::string& dir, int samples, int shards, const std::string& out,
                                          int bounces) {
    std::string mode = "mode = \"interreflected\"";
    if (bounces >= 0) mode += "\nbounces = " + std::to_string(bounces);
    return replaceAll(twoSpheresPipeline(dir, samples, shards, out), "mode = \"shadowed\"", mode);
}

inline RunOptions testOptions(const std::string& cacheDir) {
    RunOptions options;
    options.prt = kPrt;
    options.cacheDir = cacheDir;
    options.threads = 2;
    options.askPrt = cli::inProcessAnswers(hashMemoFile(options)); // as `prt run` does
    return options;
}

// Stage id -> "ran" | "cached" | "not run" | "failed".
inline std::map<std::string, std::string> statuses(const nlohmann::json& report) {
    std::map<std::string, std::string> result;
    for (const nlohmann::json& stage : report["stages"]) result[stage["id"]] = stage["status"];
    return result;
}

inline std::set<std::string> ranStages(const nlohmann::json& report) {
    std::set<std::string> ran;
    for (const nlohmann::json& stage : report["stages"])
        if (stage["status"] == "ran") ran.insert(stage["id"].get<std::string>());
    return ran;
}

// Output name -> content hash, as the run copied them.
inline std::map<std::string, std::string> outputHashes(const nlohmann::json& report) {
    std::map<std::string, std::string> hashes;
    for (auto& [name, output] : report["outputs"].items()) hashes[name] = hashFile(output["path"]);
    return hashes;
}

// Every entry of the store is complete: a manifest whose outputs exist with the recorded content hashes.
// Hidden folders (.tmp-, .old-) are private to a writer and are not entries.
inline void expectStoreConsistent(const std::string& store) {
    std::error_code error;
    if (!std::filesystem::is_directory(store, error)) return;
    for (const auto& item : std::filesystem::directory_iterator(store)) {
        std::string name = item.path().filename().string();
        if (name[0] == '.') continue;
        std::string manifestPath = item.path().string() + "/manifest.json";
        ASSERT_TRUE(std::filesystem::is_regular_file(manifestPath)) << "entry without manifest: " << name;
        nlohmann::json manifest = nlohmann::json::parse(readFileBytes(manifestPath));
        EXPECT_EQ(manifest["key"].get<std::string>(), "xxh128:" + name);
        EXPECT_EQ(keyOf(manifest["ingredients"]), manifest["key"].get<std::string>());
        for (auto& [port, output] : manifest["outputs"].items())
            EXPECT_EQ(hashFile(item.path().string() + "/" + output["file"].get<std::string>()), output["hash"].get<std::string>())
                << name << " " << port;
    }
}

// Runs a pipeline in this process with logging silenced.
inline nlohmann::json runQuietly(const Pipeline& pipeline, const RunOptions& options) {
    LogOptions quiet;
    quiet.quiet = true;
    setLogOptions(quiet);
    return runPipeline(pipeline, options);
}

} // namespace prt::test
