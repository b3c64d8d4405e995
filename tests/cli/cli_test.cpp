#include "cli_util.h"
#include "core.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

using Result = prt::test::ShellRun; // stdout and stderr together

Result runPrt(const std::string& args) { return prt::test::runShell(std::string(PRT_BINARY_DIR) + "/prt " + args); }

fs::path scratch() {
    fs::path dir = fs::temp_directory_path() / ("prt_cli_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir;
}

// Every failure must leave the output folder exactly as it was: no artifact, no temporary file.
bool folderIsEmpty(const fs::path& dir) { return fs::is_empty(dir); }

std::string dataFile(const std::string& name) { return std::string(PRT_DATA_DIR) + "/" + name; }

} // namespace

TEST(Cli, VersionAndHelp) {
    Result version = runPrt("--version");
    EXPECT_EQ(version.exitCode, 0);
    EXPECT_NE(version.output.find("prt "), std::string::npos);
    Result help = runPrt("--help");
    EXPECT_EQ(help.exitCode, 0);
    for (const char* stage : {"meshprep", "envsh", "transfer", "reference", "relight", "compare"})
        EXPECT_NE(help.output.find(stage), std::string::npos) << stage;
}

TEST(Cli, UnknownCommandIsAUsageError) {
    EXPECT_EQ(runPrt("frobnicate").exitCode, prt::kExitUsage);
    EXPECT_EQ(runPrt("").exitCode, prt::kExitUsage);
}

TEST(Cli, EnvshBadInputsExitNonZeroAndLeaveNoOutput) {
    fs::path dir = scratch() / "envsh";
    fs::create_directories(dir);
    std::string out = (dir / "sh.json").string();

    Result missing = runPrt("envsh /no/such/map.exr --order 3 -o " + out);
    EXPECT_EQ(missing.exitCode, prt::kExitInput);
    EXPECT_NE(missing.output.find("/no/such/map.exr"), std::string::npos) << missing.output;
    EXPECT_TRUE(folderIsEmpty(dir));

    fs::path notImage = scratch() / "text.exr";
    prt::writeBytesAtomic(notImage.string(), "this is not an image\n");
    Result bad = runPrt("envsh " + notImage.string() + " --order 3 -o " + out);
    EXPECT_EQ(bad.exitCode, prt::kExitInput);
    EXPECT_NE(bad.output.find("text.exr"), std::string::npos) << bad.output;
    EXPECT_TRUE(folderIsEmpty(dir));

    EXPECT_EQ(runPrt("envsh " + dataFile("env/courtyard.exr") + " --order 0 -o " + out).exitCode, prt::kExitUsage);
    EXPECT_EQ(runPrt("envsh " + dataFile("env/courtyard.exr") + " --order 3 --window gauss -o " + out).exitCode,
              prt::kExitUsage);
    EXPECT_TRUE(folderIsEmpty(dir));
}

TEST(Cli, EnvshWritesCoefficientsConventionAndHash) {
    std::string env = dataFile("env/courtyard.exr");
    ASSERT_TRUE(fs::exists(env)) << "run `make -f Makefile.data` first";
    fs::path out = scratch() / "courtyard.json";
    Result run = runPrt("--quiet envsh " + env + " --order 4 --window hann -o " + out.string());
    ASSERT_EQ(run.exitCode, 0) << run.output;
    nlohmann::json sh = nlohmann::json::parse(prt::readFileBytes(out.string()));
    EXPECT_EQ(sh["order"], 4);
    EXPECT_EQ(sh["coefficients"].size(), 16u);
    EXPECT_EQ(sh["coefficients"][0].size(), 3u);
    EXPECT_GT(sh["coefficients"][0][0].get<double>(), 0.0);
    EXPECT_EQ(sh["input"]["hash"], prt::hashFile(env));
    EXPECT_TRUE(sh.contains("convention"));
}

TEST(Cli, LogJsonEmitsJsonLines) {
    std::string env = dataFile("env/courtyard.exr");
    ASSERT_TRUE(fs::exists(env));
    fs::path out = scratch() / "json.json";
    Result run = runPrt("--log-json envsh " + env + " --order 2 -o " + out.string());
    ASSERT_EQ(run.exitCode, 0) << run.output;
    size_t lines = 0, start = 0;
    while (start < run.output.size()) {
        size_t end = run.output.find('\n', start);
        std::string line = run.output.substr(start, end - start);
        if (!line.empty()) {
            EXPECT_TRUE(nlohmann::json::accept(line)) << line;
            ++lines;
        }
        if (end == std::string::npos) break;
        start = end + 1;
    }
    EXPECT_GT(lines, 0u);
}
