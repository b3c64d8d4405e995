// The command-line layer: one file per subcommand in this folder, each a thin parser over library calls.
// `prt NAME ...` and the standalone `prt-NAME ...` run the same code.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {
struct PinholeCamera; // raycast.h
}

namespace prt::cli {

// Adds one subcommand to `app`. The subcommand's callback does the work and throws prt::Error on bad input;
// the driver maps that to a message and an exit code.
void addEnvshCommand(CLI::App& app);
void addMeshprepCommand(CLI::App& app);
void addSceneCommand(CLI::App& app);
void addTransferCommand(CLI::App& app);
void addReferenceCommand(CLI::App& app);
void addRelightCommand(CLI::App& app);
void addCompareCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addMergeCommand(CLI::App& app);
void addBakeCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addEnvlightCommand(CLI::App& app);
void addAdaptCommand(CLI::App& app);
void addFivCommand(CLI::App& app);
void addFivVisibilityCommand(CLI::App& app);
void addFivshadeCommand(CLI::App& app);
void addFivsceneCommand(CLI::App& app);
void addGlossyCommand(CLI::App& app);
void addServeCommand(CLI::App& app);
void addSpecularCommand(CLI::App& app);
void addAutoconfigCommand(CLI::App& app);

// What a pipeline cache key holds about this prt (`prt --build-info`): its version, build type, compiler, the
// content hash of its executable, and the versions of the libraries it was compiled against and has loaded.
nlohmann::json buildInfo();

// Runs the driver. With `onlyCommand`, behaves as if argv[1] were that subcommand (the standalone apps).
// With `answer`, only --build-info and --resolved-options are answered, into *answer (`prt run` asks itself
// these in-process instead of starting prt again); anything else is a usage error.
int runDriver(int argc, char** argv, const char* onlyCommand = nullptr, nlohmann::json* answer = nullptr);

// Marks `option` as naming a file the command writes besides -o (shown as OUTPUT in --help), and returns it. Before
// the command runs, the driver checks every output's path: its folder exists, it is not a folder, no two outputs
// share it, and it is none of the command's input files.
inline constexpr const char* kOutputTypeName = "OUTPUT";
CLI::Option* outputFile(CLI::Option* option);

// Makes `option` of `command` need `needed` (CLI11's needs: given without it, a usage error names both), for the
// options that only mean something beside another and would otherwise be accepted and ignored. Both must exist.
void optionNeeds(CLI::App* command, const char* option, const char* needed);

// Parses --albedo: "R,G,B" or a single grey value, each in [0, 1], kept in double so bundles record what was
// typed. Throws prt::Error(kExitUsage) naming --albedo otherwise.
std::array<double, 3> parseAlbedo(const std::string& text);

// Parses --shard "I/N" with 0 <= I < N into index I and count N. Throws prt::Error(kExitUsage) naming --shard
// otherwise.
void parseShard(const std::string& text, int& index, int& count);

// Parses --brdf "phong:EXPONENT,KS" (EXPONENT > 0, KS in [0, 1]) into exponent and ks. Throws
// prt::Error(kExitUsage) naming --brdf otherwise.
void parsePhongBrdf(const std::string& text, double& exponent, double& ks);

// Parses a pinhole camera as `prt reference --image` and `prt render` take it: `size` "W,H" (given by the option
// `sizeOption`) and `view` "EYEX,EYEY,EYEZ,TARGETX,TARGETY,TARGETZ,UPX,UPY,UPZ,FOVY" (--camera, FOVY in degrees).
// Throws prt::Error(kExitUsage) naming the option for anything else, eye == target or up along the view.
void parsePinholeCamera(const std::string& size, const char* sizeOption, const std::string& view,
                        PinholeCamera& camera);
// Parses "X,Y,Z": exactly three finite numbers. Throws prt::Error(kExitUsage) naming `option` otherwise.
std::array<float, 3> parsePoint(const std::string& text, const char* option);

// `prt relight --brdf` (relight_specular.cpp): specular through SH triple products on a bundle's
// "specular_visibility" layer. addSpecularRelightOptions adds the options to relight's command;
// runSpecularRelight runs when --brdf is given, toward --eye, under --env, writing per-vertex radiance to `output`
// (with the transfer layer's diffuse part unless glossyOnly). Throws prt::Error on bad input.
struct SpecularRelightArgs {
    std::string brdf;           // phong:N,KS; empty: not a specular relight
    int lightOrder = 0;         // 0: the visibility's order
    int productBands = 0;       // 0: the visibility's order
    double bandTolerance = 0.02; // specular::kDefaultBandTolerance
};
void addSpecularRelightOptions(CLI::App* command, SpecularRelightArgs& args);
void runSpecularRelight(const SpecularRelightArgs& args, const std::string& bundle, const std::string& env,
                        const std::string& eye, const std::string& output, bool glossyOnly);

// checkedProduct (core.h) for a size given on the command line: the element cap refuses it as a usage error
// (prt::Error(kExitUsage) naming `option`) before anything is allocated. Returns the product.
uint64_t checkCommandLineSize(const std::vector<uint64_t>& factors, const std::string& what, const char* option);

// Number of worker threads to use for --threads: `requested` if positive, the hardware concurrency for 0. Throws
// prt::Error(kExitUsage) naming --threads for a negative count.
int resolveThreads(int requested);

} // namespace prt::cli
