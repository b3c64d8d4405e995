// OpenImageIO is loaded only by stages that read or write an image (lib/image/image_library.h): the driver does not
// link it, a cache key (`prt --build-info`) never loads it yet still covers it, and a broken module is refused by
// name.
#include "cli_util.h"
#include "core.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using Ran = prt::test::ShellRun;

Ran run(const std::string& command, bool withStderr = true) { return prt::test::runShell(command, withStderr); }

const std::string kBuild = PRT_BINARY_DIR;

TEST(ImageModule, TheDriverDoesNotLinkOpenImageIO) {
    Ran ldd = run("ldd " + kBuild + "/prt-driver");
    ASSERT_EQ(ldd.exitCode, 0) << ldd.output;
    EXPECT_EQ(ldd.output.find("libOpenImageIO"), std::string::npos) << ldd.output;
    Ran module = run("ldd " + kBuild + "/prt_oiio.so");
    ASSERT_EQ(module.exitCode, 0) << module.output;
    EXPECT_NE(module.output.find("libOpenImageIO"), std::string::npos) << module.output;
}

TEST(ImageModule, BuildInfoCoversTheModuleAndItsLibraries) {
    Ran info = run(kBuild + "/prt --build-info", false);
    ASSERT_EQ(info.exitCode, 0) << info.output;
    nlohmann::json build = nlohmann::json::parse(info.output);
    EXPECT_EQ(build["image_module"], prt::hashFile(kBuild + "/prt_oiio.so"));
    bool listed = false;
    for (const nlohmann::json& library : build["libraries"]["loaded"])
        listed = listed || library.get<std::string>().rfind("libOpenImageIO.so", 0) == 0;
    EXPECT_TRUE(listed) << "the module's OpenImageIO is missing from libraries.loaded: " << build.dump(1);
}

// A copy of the driver with a file that is not a module next to it: that file wins the search (the executable's
// folder comes first). The cache key is computed without loading it; a stage that reads an image refuses it.
TEST(ImageModule, ABrokenModuleIsRefusedByNameAndNotLoadedForKeys) {
    fs::path dir = fs::temp_directory_path() / ("prt_image_module_test_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::copy_file(kBuild + "/prt-driver", dir / "prt-driver");
    fs::copy_file(kBuild + "/prt-driver.libs", dir / "prt-driver.libs");
    std::ofstream(dir / "prt_oiio.so") << "not a shared library\n";

    Ran info = run((dir / "prt-driver").string() + " --build-info", false);
    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_EQ(nlohmann::json::parse(info.output)["image_module"], prt::hashFile((dir / "prt_oiio.so").string()));

    fs::path out = dir / "sh.json";
    Ran envsh = run((dir / "prt-driver").string() + " envsh " + PRT_DATA_DIR + "/env/courtyard.exr --order 2 -o " +
                    out.string());
    EXPECT_EQ(envsh.exitCode, prt::kExitFailure) << envsh.output;
    EXPECT_NE(envsh.output.find((dir / "prt_oiio.so").string() + ": cannot load it"), std::string::npos)
        << envsh.output;
    EXPECT_FALSE(fs::exists(out));
    fs::remove_all(dir);
}

} // namespace
