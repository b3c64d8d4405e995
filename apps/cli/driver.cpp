#include "cli.h"

#include "core.h"

#include <csignal>
#include <cstdio>
#include <exception>
#include <vector>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

int runDriver(int argc, char** argv, const char* onlyCommand) {
    std::vector<char*> args(argv, argv + argc);
    std::string command = onlyCommand ? onlyCommand : "";
    if (onlyCommand) args.insert(args.begin() + 1, command.data());

    CLI::App app{"prt: precomputed radiance transfer toolchain", "prt"};
    app.set_version_flag("--version", std::string("prt ") + PRT_VERSION);
    app.require_subcommand(1);
    app.fallthrough();
    LogOptions log;
    app.add_flag("-q,--quiet", log.quiet, "No progress or info output on stderr");
    app.add_flag("--log-json", log.json, "Log to stderr as JSON lines");
    app.parse_complete_callback([&] { setLogOptions(log); });

    addSceneCommand(app);
    addMeshprepCommand(app);
    addEnvshCommand(app);
    addTransferCommand(app);
    addBakeCommand(app);
    addFivCommand(app);
    addFivVisibilityCommand(app);
    addFivshadeCommand(app);
    addGlossyCommand(app);
    addReferenceCommand(app);
    addRelightCommand(app);
    addCompareCommand(app);
    addBenchCommand(app);
    addRunCommand(app);
    addMergeCommand(app);
    addRenderCommand(app);
    addEnvlightCommand(app);
    addAdaptCommand(app);

    try {
        app.parse(int(args.size()), args.data());
    } catch (const CLI::ParseError& e) {
        // CLI11's own codes (106, 109, ...) would collide with ours; help and version are successes.
        return app.exit(e) == 0 ? kExitOk : kExitUsage;
    } catch (const Error& e) {
        logError(e.what());
        return e.exitCode();
    } catch (const std::exception& e) {
        logError(std::string("internal error: ") + e.what());
        return kExitFailure;
    }
    return kExitOk;
}

} // namespace prt::cli
