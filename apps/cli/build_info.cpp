// `prt --build-info` and `prt --resolved-options STAGE ...`: what a pipeline cache key needs to know about this
// prt, printed as JSON, so that a key changes whenever the bytes a stage writes could.
#include "cli.h"

#include "core.h"

#include <CLI/Version.hpp>
#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/imageio.h>
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

// The real file names (and sizes) of the shared libraries mapped into this process: their names carry the full version
// (libembree3.so.3.13.5, libOpenImageIO.so.2.4.7.1, libm.so.6 of a given glibc is named by its package), so an
// upgraded library changes the list even when prt itself was not rebuilt.
std::vector<std::string> loadedLibraries() {
    std::ifstream maps("/proc/self/maps");
    std::set<std::string> names;
    std::string line;
    while (std::getline(maps, line)) {
        size_t slash = line.find('/');
        if (slash == std::string::npos || line.find(".so", slash) == std::string::npos) continue;
        std::error_code error;
        std::filesystem::path real = std::filesystem::canonical(line.substr(slash), error);
        std::string name = (error ? std::filesystem::path(line.substr(slash)) : real).filename().string();
        std::error_code sizeError;
        uintmax_t bytes = std::filesystem::file_size(error ? std::filesystem::path(line.substr(slash)) : real, sizeError);
        names.insert(name + (sizeError ? "" : " " + std::to_string(bytes) + " bytes"));
    }
    return {names.begin(), names.end()};
}

// Taken before main: the libraries the executable links, whatever it loads later (plugins, OpenCL drivers), so
// that asking in-process and asking a fresh prt give the same answer.
const std::vector<std::string> kLinkedLibraries = loadedLibraries();

} // namespace

nlohmann::json buildInfo() {
    std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
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
    nlohmann::json running = {{"openimageio", OIIO::openimageio_version()}, {"tbb", TBB_runtime_version()}};
    return {{"prt", PRT_VERSION},
            {"build_type", PRT_BUILD_TYPE},
            {"compiler", __VERSION__},
            {"executable", hashFile(self)},
            {"libraries", {{"compiled", compiled}, {"running", running}, {"loaded", kLinkedLibraries}}}};
}

} // namespace prt::cli
