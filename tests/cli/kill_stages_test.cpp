// Kill each stage anywhere, by the checkpoint hook (core.h: PRT_KILL_AT, PRT_KILL_COUNTER) rather than by sleeping:
// a clean run of the stage counts its checkpoints (command start, progress steps, before and after each rename);
// then runs die by SIGKILL at points spread over them. After every kill each output is absent or byte for byte the
// clean run's (never partial), and a rerun gives the clean bytes. (A kill between writing and renaming leaves the
// hidden temporary .NAME.tmp-HOST-PID-N-R behind, never read, until the next write of that output on the host
// removes it.)
// `prt run` and the bake have their own kill tests (tests/pipeline/kill_test.cpp, tests/bake/cli_test.cpp).
#include "core.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using prt::readFileBytes;

namespace {

const std::string kPrt = std::string(PRT_BINARY_DIR) + "/prt";

struct Folder {
    fs::path path = fs::temp_directory_path() / ("prt_kill_stages_" + std::to_string(getpid()));
    Folder() {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~Folder() { fs::remove_all(path); }
    std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// Runs `prt --quiet ARGS` in the folder with the hook's environment; returns the wait status.
int runStage(const Folder& dir, const std::string& args, const std::string& environment) {
    std::string command = "cd " + dir.path.string() + " && " + environment + " " + kPrt + " --quiet " + args +
                          " >/dev/null 2>>" + (dir / "log.txt");
    return std::system(command.c_str());
}

struct StageCase {
    std::string name;
    std::string args;                 // run in the folder, after the inputs exist
    std::vector<std::string> outputs; // relative to the folder
};

} // namespace

TEST(KillStages, EveryStageKilledAnywhereLeavesWholeOutputsOrNoneAndRerunsToTheSameBytes) {
    Folder dir;
    const std::string data = PRT_DATA_DIR;
    auto setup = [&](const std::string& args) {
        ASSERT_EQ(runStage(dir, args, ""), 0) << args << "\n" << readFileBytes(dir / "log.txt");
    };
    setup("scene two-spheres -o spheres.glb");
    setup("scene sphere -o sphere.glb");
    setup("scene plane -o plane.glb");
    setup("transfer spheres.glb --mode shadowed --order 3 --samples 64 -o base.glb");
    setup("reference spheres.glb --env " + data + "/env/sunrise.exr --samples 8 --bounces 0 -o base-ref.npy");
    setup("relight base.glb --env " + data + "/env/sunrise.exr -o base-relit.npy");
    setup("fiv sphere.glb --env " + data + "/env/sunrise.exr --grid 8,5,3 --cube 8 -o sphere.fiv.glb");
    setup("transfer spheres.glb --mode shadowed --order 3 --samples 64 --shard 0/2 -o shard0.glb");
    setup("transfer spheres.glb --mode shadowed --order 3 --samples 64 --shard 1/2 -o shard1.glb");
    const std::string env = " --env " + data + "/env/sunrise.exr";
    const std::vector<StageCase> stages = {
        {"meshprep", "meshprep " + data + "/bunny.ply -o prep.glb", {"prep.glb"}},
        {"envsh", "envsh " + data + "/env/sunrise.exr --order 4 -o env.sh.json", {"env.sh.json"}},
        {"transfer", "transfer spheres.glb --mode interreflected --bounces 1 --order 3 --samples 64 -o t.glb", {"t.glb"}},
        {"reference", "reference spheres.glb" + env + " --samples 8 --bounces 1 -o ref.npy", {"ref.npy"}},
        {"relight", "relight base.glb" + env + " -o relit.npy", {"relit.npy"}},
        {"compare", "compare base-relit.npy base-ref.npy -o metrics.json", {"metrics.json"}},
        {"render", "render base.glb" + env + " --camera 0,1,3.6,0,0,0,0,1,0,40 --size 48,36 -o picture.png",
         {"picture.png"}},
        {"merge", "merge shard0.glb shard1.glb -o merged.glb", {"merged.glb"}},
        {"fiv", "fiv sphere.glb" + env + " --grid 8,5,3 --cube 8 -o again.fiv.glb", {"again.fiv.glb"}},
        {"fivshade", "fivshade plane.glb" + env + " --occluder sphere.fiv.glb --at 0,1,0 -o shade.npy", {"shade.npy"}},
        {"envlight", "envlight " + data + "/env/sunrise.exr --order 3 --max-lights 2 -o lights.json", {"lights.json"}},
        {"adapt", "adapt base.glb --max-error 0.05" + env + " -o adaptive.glb", {"adaptive.glb"}},
        {"glossy", "glossy sphere.glb --brdf phong:8,0.5 --lobes 1 --grid 4 --samples 64 -o glossy.glb",
         {"glossy.glb"}},
        {"specular", "specular base.glb --order 4 --samples 64 -o specular.glb", {"specular.glb"}},
    };
    size_t kills = 0, points = 0;
    for (const StageCase& stage : stages) {
        SCOPED_TRACE(stage.name);
        // The clean run: its outputs and its checkpoint count.
        std::string counter = dir / ("count-" + stage.name);
        ASSERT_EQ(runStage(dir, stage.args, "PRT_KILL_COUNTER=" + counter), 0) << readFileBytes(dir / "log.txt");
        std::vector<std::string> clean;
        for (const std::string& output : stage.outputs) clean.push_back(readFileBytes(dir / output));
        const long total = long(fs::file_size(counter));
        ASSERT_GE(total, 2) << "a stage passes at least its start and its rename";
        // Every point of a short stage, else the first three and five spread to the end (progress steps follow the
        // clock, so the count varies by a few and a late point may lie past a run's end).
        std::vector<long> at;
        if (total <= 8) {
            for (long k = 1; k <= total; ++k) at.push_back(k);
        } else {
            at = {1, 2, 3};
            for (int k = 1; k <= 5; ++k) at.push_back(std::max(4L, total * k / 5));
        }
        for (long point : at) {
            SCOPED_TRACE("killed at checkpoint " + std::to_string(point) + " of " + std::to_string(total));
            for (const std::string& output : stage.outputs) fs::remove(dir / output);
            std::string run = dir / ("count-" + stage.name + "-" + std::to_string(point));
            int status = runStage(dir, stage.args, "PRT_KILL_AT=" + std::to_string(point) + " PRT_KILL_COUNTER=" + run);
            bool killed = !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
            kills += killed;
            ++points;
            for (size_t o = 0; o < stage.outputs.size(); ++o) {
                std::string path = dir / stage.outputs[o];
                if (fs::exists(path)) EXPECT_EQ(readFileBytes(path), clean[o]) << path << " is partial";
                else EXPECT_TRUE(killed) << path << " is missing after a run that exited 0";
            }
            // The rerun, without the hook, gives the clean bytes.
            ASSERT_EQ(runStage(dir, stage.args, ""), 0) << readFileBytes(dir / "log.txt");
            for (size_t o = 0; o < stage.outputs.size(); ++o)
                EXPECT_EQ(readFileBytes(dir / stage.outputs[o]), clean[o]) << stage.outputs[o] << " differs on rerun";
        }
    }
    std::printf("kill stages: %zu stages, %zu kill points, %zu runs killed\n", stages.size(), points, kills);
    EXPECT_GE(kills * 10, points * 8) << "most points should kill the stage";
}
