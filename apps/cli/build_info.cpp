// `prt --build-info` and `prt --resolved-options STAGE ...`: what a pipeline cache key needs to know about this
// prt, printed as JSON, so that a key changes whenever the bytes a stage writes could.
#include "build_info.h"
#include "cli.h"

#include "core.h"
#include "image_library.h"
#include "pipeline.h"

#include <CLI/Version.hpp>
#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/oiioversion.h>
#include <OpenMesh/Core/System/config.h>
#include <embree3/rtcore.h>
#include <nlohmann/json.hpp>
#include <oneapi/tbb/version.h>
#include <toml++/toml.h>
#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <set>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif
#ifndef PRT_BUILD_TYPE
#define PRT_BUILD_TYPE "unknown"
#endif

namespace prt::cli {

namespace {

// The libraries mapped into this process before main: those the executable links, whatever it loads later
// (plugins, OpenCL drivers). Their paths as the loader found them.
std::vector<std::string> linkedLibraryPaths() {
    std::ifstream maps("/proc/self/maps");
    std::set<std::string> paths;
    std::string line;
    while (std::getline(maps, line)) {
        size_t slash = line.find('/');
        if (slash == std::string::npos || line.find(".so", slash) == std::string::npos) continue;
        paths.insert(line.substr(slash));
    }
    return {paths.begin(), paths.end()};
}
const std::vector<std::string> kLinkedLibraryPaths = linkedLibraryPaths();

// "libembree3.so.3.13.5 1234 bytes": the real file name behind `path` and its size. The names carry the full
// version (libembree3.so.3.13.5, libOpenImageIO.so.2.4.7.1, a glibc's libm.so.6 is named by its package), so an
// upgraded library changes the entry even when prt itself was not rebuilt.
std::string libraryIdentity(const std::string& path) {
    std::error_code error;
    std::filesystem::path real = std::filesystem::canonical(path, error);
    std::filesystem::path file = error ? std::filesystem::path(path) : real;
    std::error_code sizeError;
    uintmax_t bytes = std::filesystem::file_size(file, sizeError);
    return file.filename().string() + (sizeError ? "" : " " + std::to_string(bytes) + " bytes");
}

} // namespace

void writeLinkedLibraries(const std::string& path) {
    // The image module is loaded only when a stage reads or writes an image, but its libraries (OpenImageIO and
    // the ~260 it pulls in) shape those stages' outputs: load it here, at build time, and list them too.
    imageLibraryVersion();
    std::set<std::string> paths(kLinkedLibraryPaths.begin(), kLinkedLibraryPaths.end());
    for (const std::string& loaded : linkedLibraryPaths()) paths.insert(loaded);
    writeBytesAtomic(path, nlohmann::json(std::vector<std::string>(paths.begin(), paths.end())).dump(1) + "\n");
}

std::string driverOf(const std::string& program) {
    std::filesystem::path path(program);
    return (path.parent_path() / "prt-driver").string();
}

nlohmann::json buildInfo(const std::string& driver, const std::string& memoFile) {
    // The driver's linked libraries, as its link step recorded them (apps/CMakeLists.txt): the same answer in
    // every process that asks, whatever that process links itself.
    std::string listFile = driver + ".libs";
    nlohmann::json paths = nlohmann::json::parse(readFileBytes(listFile), nullptr, false);
    if (!paths.is_array())
        throw Error(listFile, "", "is not the JSON list of the driver's libraries its build writes: rebuild prt", kExitFailure);
    std::set<std::string> loaded;
    for (const nlohmann::json& path : paths)
        if (path.is_string()) loaded.insert(libraryIdentity(path.get<std::string>()));
    nlohmann::json compiled = {
        {"cli11", CLI11_VERSION},
        {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                      std::to_string(EIGEN_MINOR_VERSION)},
        {"embree", RTC_VERSION_STRING},
        {"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." + std::to_string(NLOHMANN_JSON_VERSION_MINOR) +
                              "." + std::to_string(NLOHMANN_JSON_VERSION_PATCH)},
        {"openexr", OPENEXR_VERSION_STRING},
        {"openimageio", OIIO_VERSION_STRING},
        {"openmesh", OM_VERSION},
        {"tbb", TBB_VERSION_STRING},
        {"tomlplusplus", std::to_string(TOML_LIB_MAJOR) + "." + std::to_string(TOML_LIB_MINOR) + "." +
                             std::to_string(TOML_LIB_PATCH)}};
    // The image module the driver's stages will load (image_library.h's rule), by content hash: never loaded here,
    // so a cache key costs no OpenImageIO start-up; its OpenImageIO version is the header's above.
    std::string imageModule = findImageModule(driver);
    return {{"prt", PRT_VERSION},
            {"build_type", PRT_BUILD_TYPE},
            {"compiler", __VERSION__},
            {"executable", hashFileMemo(driver, memoFile)},
            {"image_module", imageModule.empty() ? std::string("none") : hashFileMemo(imageModule, memoFile)},
            {"libraries", {{"compiled", compiled}, {"loaded", std::vector<std::string>(loaded.begin(), loaded.end())}}}};
}

nlohmann::json buildInfo() { return buildInfo(driverOf(std::filesystem::read_symlink("/proc/self/exe").string()), ""); }

std::function<nlohmann::json(const std::vector<std::string>&)> inProcessAnswers(const std::string& memoFile) {
    return [memoFile](const std::vector<std::string>& question) {
        if (question.size() == 2 && question[1] == "--build-info") return buildInfo(driverOf(question[0]), memoFile);
        std::vector<std::string> words = question;
        std::vector<char*> argv;
        for (std::string& word : words) argv.push_back(word.data());
        nlohmann::json answer;
        if (runDriver(int(argv.size()), argv.data(), nullptr, &answer) != kExitOk || !answer.is_object())
            throw Error("", "cache key", "prt could not resolve the options of `" + question.back() + "`", kExitFailure);
        return answer;
    };
}

} // namespace prt::cli
