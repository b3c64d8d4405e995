#include "build_info.h"
#include "cli.h"

#include "core.h"
#include "utf8.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <new>
#include <vector>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

// Whether the command line asks for JSON logs: for the errors reported before its flags are parsed.
bool wantsJsonLog(int argc, char** argv) {
    return std::any_of(argv + 1, argv + argc, [](const char* a) { return std::strcmp(a, "--log-json") == 0; });
}

// The option's name as a message shows it: its long name, else its positional name.
std::string optionName(const CLI::Option& option) {
    return option.get_lnames().empty() ? option.get_name() : "--" + option.get_lnames().front();
}

// Every number a command takes is finite: CLI11 reads "nan", "inf" and "1e999" as doubles, and no stage has a use
// for them (a NaN angle reached Embree's ray check, an infinite tolerance a bundle's JSON). Throws prt::Error
// (kExitUsage) naming the option.
void checkFiniteNumbers(const CLI::App& command) {
    for (const CLI::Option* option : command.get_options()) {
        if (option->get_type_name().rfind("FLOAT", 0) != 0) continue;
        for (const std::string& text : option->results()) {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && *end == '\0' && !std::isfinite(value))
                throw Error("", optionName(*option), "'" + text + "' is not a finite number", kExitUsage);
        }
    }
}

// Before a command computes anything: each file it writes (-o and the options marked by outputFile) has an
// existing folder (else kExitOutput), is not a folder itself, is written by one option only, and is none of the
// existing files the command's other options name, its inputs (else kExitUsage): an output written over its input
// would lose the input, or be read half-written by the stage itself.
void checkOutputPaths(const CLI::App& command) {
    namespace fs = std::filesystem;
    std::vector<std::pair<std::string, std::string>> outputs, others; // (option, path)
    for (const CLI::Option* option : command.get_options()) {
        const bool output = option->check_lname("output") || option->get_type_name() == kOutputTypeName;
        for (const std::string& path : option->results()) (output ? outputs : others).push_back({optionName(*option), path});
    }
    std::error_code error;
    for (size_t i = 0; i < outputs.size(); ++i) {
        const auto& [flag, path] = outputs[i];
        const fs::path folder = fs::path(path).parent_path();
        if (!folder.empty() && !fs::is_directory(folder, error))
            throw Error(path, flag, "its folder " + folder.string() + " does not exist", kExitOutput);
        if (fs::is_directory(path, error)) throw Error(path, flag, "is a folder, not a file to write", kExitOutput);
        const fs::path resolved = fs::weakly_canonical(fs::absolute(path, error), error);
        for (size_t j = 0; j < i; ++j)
            if (fs::weakly_canonical(fs::absolute(outputs[j].second, error), error) == resolved)
                throw Error(path, flag, "is also the output of " + outputs[j].first + ": give each output its own file",
                            kExitUsage);
        if (!fs::exists(path, error)) continue;
        for (const auto& [otherFlag, other] : others)
            if (fs::is_regular_file(other, error) && fs::equivalent(path, other, error))
                throw Error(path, flag, "is also the input given as " + otherFlag + ": write the output elsewhere",
                            kExitUsage);
    }
}

} // namespace

int runDriver(int argc, char** argv, const char* onlyCommand, nlohmann::json* answer) {
    std::vector<char*> args(argv, argv + argc);
    // File names and values go into JSON (reports, logs, bundles, cache keys), which holds UTF-8 only.
    for (int i = 1; i < argc; ++i)
        if (!isUtf8(argv[i])) {
            const std::string shown = printableBytes(argv[i]);
            if (!answer) { // the message obeys --log-json, though the flags are not parsed yet
                LogOptions options;
                options.json = wantsJsonLog(argc, argv);
                setLogOptions(options);
            }
            logError("argument " + std::to_string(i) + " ('" + shown + "') is not UTF-8: prt writes file names and "
                     "values into JSON (reports, logs, bundles), which holds UTF-8 only; rename the file or pass the "
                     "name in UTF-8");
            return kExitUsage;
        }
    std::string command = onlyCommand ? onlyCommand : "";
    if (onlyCommand) args.insert(args.begin() + 1, command.data());

    CLI::App app{"prt: precomputed radiance transfer toolchain", "prt"};
    app.set_version_flag("--version", std::string("prt ") + PRT_VERSION);
    app.require_subcommand(0, 1);
    app.fallthrough();
    // Every option records its default, so --resolved-options can print what a stage will run with.
    app.option_defaults()->always_capture_default();
    LogOptions log;
    bool printBuildInfo = false, printResolved = false;
    app.add_flag("-q,--quiet", log.quiet, "No progress or info output on stderr");
    app.add_flag("--log-json", log.json, "Log to stderr as JSON lines");
    app.add_flag("--build-info", printBuildInfo, "Print this build's identity and library versions as JSON, and exit");
    std::string linkedLibraries;
    app.add_option("--write-linked-libraries", linkedLibraries, "Write the libraries this executable links to FILE "
                   "(JSON), and exit (its build does)")->group("");
    app.add_flag("--resolved-options", printResolved,
                 "Print the options STAGE would run with, defaults included, as JSON, and exit without running it");
    // With `answer`, the questions below are answered into it, and this process's logging is left as it is.
    auto reply = [&](const nlohmann::json& value) {
        if (answer) *answer = value;
        else std::fputs((value.dump() + "\n").c_str(), stdout);
        throw CLI::Success();
    };
    app.parse_complete_callback([&] {
        if (!answer) setLogOptions(log);
        if (!linkedLibraries.empty() && !answer) {
            writeLinkedLibraries(linkedLibraries);
            throw CLI::Success();
        }
        if (printBuildInfo) reply(buildInfo());
        if (app.get_subcommands().empty()) throw CLI::RequiredError("A subcommand");
        if (printResolved) {
            // Option name -> its values as given, or its default; positionals by name. Pipeline cache keys hold this.
            nlohmann::json resolved = nlohmann::json::object();
            std::function<void(CLI::App*)> collect = [&](CLI::App* command) {
                for (const CLI::Option* option : command->get_options()) {
                    std::string name = option->get_name(false, true);
                    if (name == "--help" || name == "-h,--help") continue;
                    resolved[name] = option->count() > 0 ? nlohmann::json(option->results())
                                                         : nlohmann::json(option->get_default_str());
                }
                // Option groups are nameless subcommands.
                for (CLI::App* group : command->get_subcommands([](CLI::App* a) { return a->get_name().empty(); }))
                    collect(group);
            };
            for (CLI::App* sub : app.get_subcommands()) collect(sub);
            reply(resolved);
        }
        if (answer) throw CLI::RequiredError("--build-info or --resolved-options");
        for (CLI::App* sub : app.get_subcommands()) {
            checkFiniteNumbers(*sub);
            checkOutputPaths(*sub);
        }
        checkpoint("command"); // the questions above are not kill points: they change nothing
    });

    addSceneCommand(app);
    addMeshprepCommand(app);
    addEnvshCommand(app);
    addTransferCommand(app);
    addBakeCommand(app);
    addFivCommand(app);
    addFivVisibilityCommand(app);
    addFivshadeCommand(app);
    addFivsceneCommand(app);
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
    addServeCommand(app);
    addSpecularCommand(app);
    addAutoconfigCommand(app);

    try {
        app.parse(int(args.size()), args.data());
    } catch (const CLI::ParseError& e) {
        // CLI11's own codes (106, 109, ...) would collide with ours; help and version are successes. With
        // --log-json a usage error is a JSON line like every other error.
        if (e.get_exit_code() != 0 && !answer && wantsJsonLog(argc, argv)) {
            LogOptions options;
            options.json = true;
            setLogOptions(options);
            logError(e.what());
            return kExitUsage;
        }
        return app.exit(e) == 0 ? kExitOk : kExitUsage;
    } catch (const Error& e) {
        logError(e.what());
        return e.exitCode();
    } catch (const std::bad_alloc&) {
        // Not a bug of prt's: the input needs more memory than the process may have.
        logError("out of memory: the inputs need more memory than this process may use (a file may claim up to "
                 "PRT_MAX_ELEMENTS elements; set PRT_MAX_ELEMENTS=N in the environment to lower that cap and have "
                 "such files refused by name)");
        return kExitFailure;
    } catch (const std::exception& e) {
        logError(std::string("internal error: ") + e.what());
        return kExitFailure;
    }
    return kExitOk;
}

} // namespace prt::cli
