#include "core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>
#include <fstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

static fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_core_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

TEST(Core, ErrorNamesFilePlaceAndProblem) {
    prt::Error e("mesh.obj", "line 12", "index 99 out of range");
    EXPECT_STREQ(e.what(), "mesh.obj: line 12: index 99 out of range");
    EXPECT_EQ(e.exitCode(), prt::kExitInput);
    EXPECT_STREQ(prt::Error("a.exr", "", "not an image").what(), "a.exr: not an image");
}

TEST(Core, AtomicWriteLeavesNothingWhenWriterThrows) {
    fs::path target = scratch("artifact.bin");
    fs::remove(target);
    EXPECT_THROW(prt::writeFileAtomic(target.string(), [](const std::string& tmp) {
                     std::ofstream(tmp) << "partial";
                     throw prt::Error("", "", "simulated failure");
                 }),
                 prt::Error);
    EXPECT_FALSE(fs::exists(target));
    for (auto& entry : fs::directory_iterator(target.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".artifact.bin.tmp"), std::string::npos) << entry.path();
}

TEST(Core, AtomicWriteReplacesWholeFile) {
    fs::path target = scratch("replace.txt");
    prt::writeBytesAtomic(target.string(), "first version, long");
    prt::writeBytesAtomic(target.string(), "second");
    EXPECT_EQ(prt::readFileBytes(target.string()), "second");
}

// A writer SIGKILLed between writing and renaming leaves its temporary file (found piling up in a pipeline's output
// folder by a session that killed `prt run` while it copied outputs out). The next write of that path on this host
// removes those of dead processes, and keeps a live process's and another host's.
TEST(Core, AtomicWriteRemovesWhatKilledWritersOfThePathLeft) {
    fs::path target = scratch("swept.bin");
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    const pid_t dead = fork();
    if (dead == 0) _exit(0);
    waitpid(dead, nullptr, 0);
    const std::string prefix = ".swept.bin.tmp-" + std::string(host) + "-";
    const fs::path stale = target.parent_path() / (prefix + std::to_string(dead) + "-0");
    const fs::path live = target.parent_path() / (prefix + std::to_string(getppid()) + "-0");
    const fs::path elsewhere = target.parent_path() / (".swept.bin.tmp-another-host-" + std::to_string(dead) + "-0");
    const fs::path otherFile = target.parent_path() / (".other.bin.tmp-" + std::string(host) + "-" + std::to_string(dead) + "-0");
    for (const fs::path& path : {stale, live, elsewhere, otherFile}) std::ofstream(path) << "left behind";
    prt::writeBytesAtomic(target.string(), "whole");
    EXPECT_FALSE(fs::exists(stale));
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(elsewhere));
    EXPECT_TRUE(fs::exists(otherFile));
    EXPECT_EQ(prt::readFileBytes(target.string()), "whole");
    for (const fs::path& path : {live, elsewhere, otherFile}) fs::remove(path);
}

// Links planted at the temporary names a writer could be guessed to use (this process's id, counters 0..63: what a
// hostile user of a shared output folder would plant) are never written through: temporaries are created as new
// files under names with 64 random bits, and the victim the links point at keeps its bytes.
TEST(Core, AtomicWriteNeverWritesThroughALinkPlantedAtATemporaryName) {
    fs::path target = scratch("planted.json");
    fs::path victim = scratch("victim.txt");
    std::ofstream(victim) << "precious";
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    const std::string prefix = ".planted.json.tmp-" + std::string(host) + "-" + std::to_string(getpid()) + "-";
    std::vector<fs::path> links;
    for (int n = 0; n < 64; ++n) {
        links.push_back(target.parent_path() / (prefix + std::to_string(n)));
        fs::create_symlink(victim, links.back());
    }
    prt::writeBytesAtomic(target.string(), "{}");
    EXPECT_EQ(prt::readFileBytes(victim.string()), "precious");
    EXPECT_FALSE(fs::is_symlink(target));
    EXPECT_EQ(prt::readFileBytes(target.string()), "{}");
    const std::string fresh = prt::freshTemporaryPath(target.string(), ".exr");
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(fresh)));
    EXPECT_EQ(fs::file_size(fresh), 0u);
    EXPECT_NE(prt::freshTemporaryPath(target.string(), ".exr"), fresh);
    EXPECT_EQ(fresh.substr(fresh.size() - 4), ".exr");
    for (const fs::path& link : links) fs::remove(link);
    for (const auto& item : fs::directory_iterator(target.parent_path()))
        if (item.path().filename().string().rfind(".planted.json.tmp-", 0) == 0) fs::remove(item.path());
}

// What every reader asks before it follows a name found in a file: inside the folder, its links resolved.
TEST(Core, ResolvedInsideFollowsLinksAndRefusesWhatLeavesTheFolder) {
    const fs::path folder = scratch("inside");
    fs::create_directories(folder / "sub");
    std::ofstream(scratch("outside.txt")) << "x";
    std::ofstream(folder / "sub" / "in.txt") << "x";
    fs::remove(folder / "out-link");
    fs::remove(folder / "in-link");
    fs::create_symlink(scratch("outside.txt"), folder / "out-link");
    fs::create_symlink(folder / "sub" / "in.txt", folder / "in-link");
    EXPECT_EQ(prt::resolvedInside((folder / "sub/in.txt").string(), folder.string()),
              fs::weakly_canonical(folder / "sub/in.txt").string());
    EXPECT_NE(prt::resolvedInside((folder / "in-link").string(), folder.string()), "");
    EXPECT_NE(prt::resolvedInside((folder / "not-yet.txt").string(), folder.string()), ""); // need not exist
    EXPECT_EQ(prt::resolvedInside((folder / "out-link").string(), folder.string()), "");
    EXPECT_EQ(prt::resolvedInside((folder / "sub/../../outside.txt").string(), folder.string()), "");
    EXPECT_EQ(prt::resolvedInside(folder.string(), folder.string()), "");
    EXPECT_EQ(prt::resolvedInside((folder.string() + "-sibling/x"), folder.string()), ""); // a prefix is not inside
}

// A result that overflowed float on the way is refused before it is written, naming its first bad value.
TEST(Core, RequireFiniteResultNamesTheFirstValueThatIsNot) {
    const float good[6] = {0, 1, 2, 3e38f, -3e38f, 5};
    EXPECT_NO_THROW(prt::requireFiniteResult(good, 6, 3, "r.npy"));
    const float bad[6] = {0, 1, 2, 3, std::numeric_limits<float>::infinity(), std::nanf("")};
    try {
        prt::requireFiniteResult(bad, 6, 3, "r.npy");
        FAIL() << "an infinite result was accepted";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), "r.npy");
        EXPECT_EQ(e.place(), "row 1, column 1");
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
    }
}

TEST(Core, ArenaConcurrencyIsAutomaticForZeroAndNeverPastTheCores) {
    EXPECT_EQ(prt::arenaConcurrency(0), -1);
    EXPECT_EQ(prt::arenaConcurrency(-3), -1);
    EXPECT_EQ(prt::arenaConcurrency(1), 1);
    EXPECT_EQ(prt::arenaConcurrency(1 << 20), std::max(1, int(std::thread::hardware_concurrency())));
}

TEST(Core, WriteIntoMissingFolderFailsCleanly) {
    fs::path target = scratch("no/such/folder/out.bin");
    EXPECT_THROW(prt::writeBytesAtomic(target.string(), "x"), prt::Error);
    EXPECT_FALSE(fs::exists(target));
}

TEST(Core, MissingFileIsAnInputError) {
    try {
        prt::readFileBytes("/nonexistent/prt/file.glb");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), "/nonexistent/prt/file.glb");
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
    }
}

TEST(Core, HashIsStableAndSensitive) {
    EXPECT_EQ(prt::hashBytes("abc", 3), prt::hashBytes("abc", 3));
    EXPECT_NE(prt::hashBytes("abc", 3), prt::hashBytes("abd", 3));
    EXPECT_EQ(prt::hashBytes("", 0).rfind("xxh128:", 0), 0u);
    fs::path file = scratch("hash.bin");
    std::string big(3 << 20, 'q'); // spans several read chunks
    big[123456] = 'z';
    prt::writeBytesAtomic(file.string(), big);
    EXPECT_EQ(prt::hashFile(file.string()), prt::hashBytes(big.data(), big.size()));
}

TEST(Core, NpyRoundTripAndValidation) {
    fs::path file = scratch("a.npy");
    std::vector<float> data = {1.f, -2.5f, 3.f, 4.f, 5.f, 6.f};
    prt::writeNpy(file.string(), data, {2, 3});
    std::vector<size_t> shape;
    EXPECT_EQ(prt::readNpy(file.string(), &shape), data);
    EXPECT_EQ(shape, (std::vector<size_t>{2, 3}));
    // Header must be 64-byte aligned as numpy writes it.
    std::string bytes = prt::readFileBytes(file.string());
    EXPECT_EQ((bytes.size() - data.size() * 4) % 64, 0u);
    // Truncated data is reported.
    prt::writeBytesAtomic(file.string(), bytes.substr(0, bytes.size() - 4));
    EXPECT_THROW(prt::readNpy(file.string(), &shape), prt::Error);
    prt::writeBytesAtomic(file.string(), "not numpy at all");
    EXPECT_THROW(prt::readNpy(file.string(), &shape), prt::Error);
}

TEST(Core, FileExtension) {
    EXPECT_EQ(prt::fileExtension("a/b/Mesh.GLB"), "glb");
    EXPECT_EQ(prt::fileExtension("a.b/mesh"), "");
    EXPECT_EQ(prt::fileExtension("x.tar.gz"), "gz");
}

namespace {
// A float32 .npy whose header claims `shape` (Python tuple text) over `floats` floats of data.
std::string npyWithShape(const std::string& shape, size_t floats) {
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }";
    header.append((64 - (10 + header.size() + 1) % 64) % 64, ' ');
    header += '\n';
    std::string bytes("\x93NUMPY\x01\x00", 8);
    bytes += char(header.size() & 0xff);
    bytes += char(header.size() >> 8);
    return bytes + header + std::string(floats * 4, '\0');
}

std::string npyRefusal(const std::string& bytes) {
    fs::path file = scratch("hostile.npy");
    prt::writeBytesAtomic(file.string(), bytes);
    try {
        std::vector<size_t> shape;
        prt::readNpy(file.string(), &shape);
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitInput) << e.what();
        return e.what();
    }
    return "";
}
} // namespace

// 2^62 + 1 times 4 wraps to 4 in 64 bits: before the fix, 16 bytes of data "matched" a shape of 2^64 floats.
TEST(Core, NpyShapeProductOverflowIsRefused) {
    std::string message = npyRefusal(npyWithShape("(4611686018427387905, 4)", 4));
    EXPECT_NE(message.find("above the limit"), std::string::npos) << message;
    message = npyRefusal(npyWithShape("(1000000000000, 3)", 3));
    EXPECT_NE(message.find("PRT_MAX_ELEMENTS"), std::string::npos) << message;
    // Text where numbers belong is a bad file (exit 3), not an internal error from std::stoull.
    EXPECT_NE(npyRefusal(npyWithShape("(abc, 3)", 3)).find("non-negative integers"), std::string::npos);
    EXPECT_NE(npyRefusal(npyWithShape("(-2, 3)", 3)).find("non-negative integers"), std::string::npos);
    EXPECT_NE(npyRefusal(npyWithShape("(99999999999999999999999, 3)", 3)).find("too large"), std::string::npos);
}

TEST(Core, ElementCapNamesTheLimitAndHowToRaiseIt) {
    EXPECT_NO_THROW(prt::checkElementCount(prt::kDefaultMaxElements, "vertices", "f", "p"));
    try {
        prt::checkElementCount(1000000000000ull, "vertices", "mesh.ply", "element vertex");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "mesh.ply: element vertex: claims 1000000000000 vertices, above the limit of 1073741824 "
                  "(PRT_MAX_ELEMENTS; set PRT_MAX_ELEMENTS=N in the environment to raise it)");
    }
    setenv("PRT_MAX_ELEMENTS", "2000000000000", 1);
    EXPECT_NO_THROW(prt::checkElementCount(1000000000000ull, "vertices", "f", "p"));
    setenv("PRT_MAX_ELEMENTS", "many", 1);
    EXPECT_THROW(prt::checkElementCount(1, "vertices", "f", "p"), prt::Error);
    unsetenv("PRT_MAX_ELEMENTS");
    EXPECT_EQ(prt::checkedProduct({0, UINT64_MAX, UINT64_MAX}, "values", "f", "p"), 0u);
    EXPECT_THROW(prt::checkedProduct({UINT64_MAX, 2}, "values", "f", "p"), prt::Error);
}
