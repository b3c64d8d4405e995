// prt serve: the browser viewer (viewer/, docs in viewer/README.md) over a folder of outputs, on 127.0.0.1.
// It runs viewer/serve.mjs under Node in place of this process: the viewer is a static page plus three.js from
// npm, so a web server written here would duplicate what a dozen lines of Node already do.
#include "cli.h"

#include "core.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include <unistd.h>

namespace prt::cli {

namespace {

struct ServeOptions {
    std::string folder;
    int port = 8000;
};

// The viewer's folder: $PRT_VIEWER_DIR, else the source tree this prt was built from.
std::string viewerFolder() {
    const char* override = std::getenv("PRT_VIEWER_DIR");
    return override && *override ? override : PRT_SOURCE_DIR "/viewer";
}

void runServe(const ServeOptions& options) {
    namespace fs = std::filesystem;
    std::error_code error;
    if (!fs::is_directory(options.folder, error))
        throw Error(options.folder, "", "is not a folder (give the folder prt run wrote its outputs to)");
    if (options.port < 0 || options.port > 65535)
        throw Error("", "--port", std::to_string(options.port) + " is not a port (0..65535; 0: a free one)", kExitUsage);
    std::string viewer = viewerFolder();
    std::string script = viewer + "/serve.mjs";
    if (!fs::is_regular_file(script, error))
        throw Error(script, "", "is missing: set PRT_VIEWER_DIR to the viewer/ folder of prt's sources");
    if (!fs::is_directory(viewer + "/node_modules/three", error))
        throw Error(viewer + "/node_modules/three", "",
                    "is missing: run `npm ci` in " + viewer + " (scripts/bootstrap.sh does)");
    // execvp with an argument vector: the folder name never passes through a shell.
    std::string port = std::to_string(options.port);
    std::vector<char*> argv = {const_cast<char*>("node"), script.data(), const_cast<char*>(options.folder.c_str()),
                               port.data(), nullptr};
    execvp("node", argv.data());
    throw Error("node", "", std::string("cannot be started (") + std::strerror(errno) +
                                "): install Node.js (scripts/bootstrap.sh does)");
}

} // namespace

void addServeCommand(CLI::App& app) {
    auto options = std::make_shared<ServeOptions>();
    CLI::App* command = app.add_subcommand(
        "serve", "Open the browser viewer over a folder of bundles, prt-sh lighting and reference radiance");
    command->add_option("folder", options->folder, "Folder served at /data/ (for example out/default)")->required();
    command->add_option("--port", options->port, "Port on 127.0.0.1 (default 8000; 0: a free one)");
    command->callback([options] { runServe(*options); });
}

} // namespace prt::cli
