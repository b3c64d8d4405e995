// Running the prt binary from tests (the folders whose tests drive the CLI include this).
#pragma once

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

// Runs `PRT_EXECUTABLE ARGUMENTS` through the shell (the arguments are the test's own), with stderr captured in
// DIR/stderr.txt and stdout left as the test's. Needs PRT_EXECUTABLE defined by the test target and DIR to exist.
inline CliRun runPrt(const std::string& arguments, const std::filesystem::path& dir) {
    std::filesystem::path log = dir / "stderr.txt";
    int status = std::system((std::string(PRT_EXECUTABLE) + " " + arguments + " 2> " + log.string()).c_str());
    std::stringstream text;
    text << std::ifstream(log).rdbuf();
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

} // namespace prt::test
