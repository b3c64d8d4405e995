// Running the prt binary from tests (the folders whose tests drive the CLI include this).
#pragma once

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

namespace prt::test {

struct CliRun {
    int exitCode;           // the exit status; -1 when a signal ended the process
    std::string stderrText; // what it wrote on stderr
};

#ifdef PRT_EXECUTABLE
// Runs `PRT_EXECUTABLE ARGUMENTS` through the shell (the arguments are the test's own), with stderr captured in
// DIR/stderr.txt and stdout left as the test's. Needs PRT_EXECUTABLE defined by the test target and DIR to exist.
inline CliRun runPrt(const std::string& arguments, const std::filesystem::path& dir) {
    std::filesystem::path log = dir / "stderr.txt";
    int status = std::system((std::string(PRT_EXECUTABLE) + " " + arguments + " 2> " + log.string()).c_str());
    std::stringstream text;
    text << std::ifstream(log).rdbuf();
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}
#endif

struct ShellRun {
    int exitCode;       // the exit status; -1 when a signal ended the process or it could not start
    std::string output; // stdout, and stderr too when asked
};

// Runs `command` through the shell (a test's own command line, never input) and captures its stdout, with stderr
// merged when `withStderr` (else discarded).
inline ShellRun runShell(const std::string& command, bool withStderr = true) {
    ShellRun result{-1, {}};
    FILE* pipe = popen((command + (withStderr ? " 2>&1" : " 2>/dev/null")).c_str(), "r");
    if (!pipe) return result;
    std::array<char, 4096> chunk;
    size_t got;
    while ((got = fread(chunk.data(), 1, chunk.size(), pipe)) > 0) result.output.append(chunk.data(), got);
    int status = pclose(pipe);
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

} // namespace prt::test
