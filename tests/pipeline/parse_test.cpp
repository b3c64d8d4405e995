// Pipeline files: the shipped ones parse, valid ones give the DAG they describe, and each malformed file in
// malformed/ fails with the line, key and problem its first line ("# expect: PLACE | PROBLEM") names.
#include "pipeline_test_util.h"

#include <algorithm>

namespace prt {
namespace {

const std::string kMalformedDir = PRT_SOURCE_DIR "/tests/pipeline/malformed";

std::vector<std::string> malformedFiles() {
    std::vector<std::string> names;
    for (const auto& item : std::filesystem::directory_iterator(kMalformedDir))
        if (item.path().extension() == ".toml") names.push_back(item.path().stem().string());
    std::sort(names.begin(), names.end());
    return names;
}

class Malformed : public testing::TestWithParam<std::string> {};

TEST_P(Malformed, FailsWithItsOwnError) {
    std::string file = kMalformedDir + "/" + GetParam() + ".toml";
    std::string text = readFileBytes(file);
    std::string expect = text.substr(0, text.find('\n'));
    ASSERT_EQ(expect.rfind("# expect: ", 0), 0u) << file << " has no '# expect:' first line";
    size_t bar = expect.find(" | ");
    std::string place = expect.substr(10, bar - 10), problem = expect.substr(bar + 3);
    try {
        parsePipeline(text, file);
        FAIL() << file << " parsed without error";
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), file);
        EXPECT_EQ(e.exitCode(), kExitInput);
        if (place.find(',') == std::string::npos) EXPECT_EQ(e.place().substr(0, place.size()), place) << e.what(); // syntax
        else EXPECT_EQ(e.place(), place) << e.what();
        EXPECT_NE(e.problem().find(problem), std::string::npos) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(Files, Malformed, testing::ValuesIn(malformedFiles()),
                         [](const testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(Malformed, ThereAreAtLeastFifteenDistinctErrors) {
    std::set<std::string> problems;
    for (const std::string& name : malformedFiles()) {
        std::string text = readFileBytes(kMalformedDir + "/" + name + ".toml");
        problems.insert(text.substr(text.find(" | "), text.find('\n') - text.find(" | ")));
    }
    EXPECT_GE(problems.size(), 15u);
}

TEST(Malformed, CommandLineNamesFileLineAndKeyAndExitsWithInputError) {
    std::string output;
    int status = test::shell(test::kPrt + " run " + kMalformedDir + "/cycle.toml", &output);
    EXPECT_EQ(status, kExitInput);
    EXPECT_NE(output.find("cycle.toml: line 9, stages.a: cycle: a -> b -> a"), std::string::npos) << output;
}

TEST(Load, MissingInputFileNamesTheInputAndItsLine) {
    test::TempDir dir;
    std::string file = dir / "p.toml";
    test::writeText(file, "[inputs]\nshape = { mesh = \"" + (dir / "absent.obj") +
                              "\" }\n[stages.prep]\nrun = \"meshprep\"\ninputs = { mesh = \"shape\" }\n"
                              "[outputs]\nmesh = { from = \"prep\", path = \"" + (dir / "out.glb") + "\" }\n");
    try {
        loadPipeline(file);
        FAIL() << "a missing input file was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.place(), "line 2, inputs.shape");
        EXPECT_NE(e.problem().find("missing input file"), std::string::npos) << e.what();
    }
}

// An output whose path differs from an input's by its text but leads to the same file (a link here; an absolute
// path or ".." alike) would be overwritten by the run: refused when the pipeline is loaded, naming the output's line.
TEST(Load, AnOutputLeadingToAnInputsFileIsRefused) {
    test::TempDir dir;
    test::writeText(dir / "shape.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::filesystem::create_symlink(dir / "shape.obj", dir / "link.glb");
    std::string file = dir / "p.toml";
    test::writeText(file, "[inputs]\nshape = { mesh = \"" + (dir / "shape.obj") +
                              "\" }\n[stages.prep]\nrun = \"meshprep\"\ninputs = { mesh = \"shape\" }\n"
                              "[outputs]\nmesh = { from = \"prep\", path = \"" + (dir / "link.glb") + "\" }\n");
    try {
        loadPipeline(file);
        FAIL() << "an output over an input's file was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.place(), "line 7, outputs.mesh.path");
        EXPECT_NE(e.problem().find("is the file of input 'shape'"), std::string::npos) << e.what();
    }
}

// A relight stage takes one lighting, or the map with its lights (a glossy bundle's lights path); env with sh is
// refused by the malformed file exactly_one_input.toml.
TEST(Parse, RelightTakesTheMapWithItsLightsForTheGlossyLightsPath) {
    const char* text = R"(
[inputs]
shape = { mesh = "shape.obj" }
sky = { env = "sky.exr" }
[stages.glossy]
run = "glossy"
inputs = { mesh = "shape" }
brdf = "phong:32,0.5"
[stages.lights]
run = "envlight"
inputs = { env = "sky" }
[stages.relight]
run = "relight"
inputs = { bundle = "glossy", env = "sky", lights = "lights" }
eye = "0,5,25"
[outputs]
radiance = { from = "relight", path = "out/r.npy" }
)";
    Pipeline pipeline = parsePipeline(text, "glossy_lights.toml");
    const PipelineStage* relight = nullptr;
    for (const PipelineStage& stage : pipeline.stages)
        if (stage.id == "relight") relight = &stage;
    ASSERT_NE(relight, nullptr);
    ASSERT_EQ(relight->inputs.size(), 3u); // bundle, env, lights
}

const char* kDiamond = R"(
[pipeline]
name = "diamond"

[inputs]
sky = { env = "sky.exr" }

[stages.last]
run = "compare"
inputs = { result = "left", reference = "right.radiance" }

[stages.left]
run = "relight"
inputs = { bundle = "transfer", env = "sky" }
rotate-y = 90

[stages.right]
run = "reference"
inputs = { mesh = "ball", env = "sky" }
albedo = [0.5, 1, 0.25]

[stages.transfer]
run = "transfer"
inputs = { mesh = "ball" }
shards = 3

[stages.ball]
run = "scene"
name = "sphere"

[outputs]
metrics = { from = "last", path = "out/metrics.json" }
)";

TEST(Parse, SortsStagesTopologicallyAndWiresPorts) {
    Pipeline pipeline = parsePipeline(kDiamond, "diamond.toml");
    EXPECT_EQ(pipeline.name, "diamond");
    std::vector<std::string> order;
    for (const PipelineStage& stage : pipeline.stages) order.push_back(stage.id);
    auto position = [&](const std::string& id) { return std::find(order.begin(), order.end(), id) - order.begin(); };
    EXPECT_LT(position("ball"), position("transfer"));
    EXPECT_LT(position("transfer"), position("left"));
    EXPECT_LT(position("ball"), position("right"));
    EXPECT_LT(position("left"), position("last"));
    EXPECT_LT(position("right"), position("last"));

    const PipelineStage& last = pipeline.stages[findStage(pipeline, "last")];
    ASSERT_EQ(last.inputs.size(), 2u);
    EXPECT_EQ(last.inputs[0].port, "result");
    EXPECT_EQ(last.inputs[0].source, "left");
    EXPECT_EQ(last.inputs[0].sourcePort, "radiance"); // a stage's first output
    EXPECT_EQ(last.inputs[1].sourcePort, "radiance");
    EXPECT_EQ(pipeline.stages[findStage(pipeline, "transfer")].shards, 3);
    EXPECT_EQ(pipeline.outputs[0].stage, "last");
    EXPECT_EQ(pipeline.outputs[0].port, "metrics");
    EXPECT_THROW(findStage(pipeline, "nowhere"), Error);
}

TEST(Parse, ParametersAreCanonicalWhateverTheSpelling) {
    Pipeline a = parsePipeline(kDiamond, "a.toml");
    std::string respelled = kDiamond;
    respelled.replace(respelled.find("rotate-y = 90"), 13, "rotate-y = 90.0");
    respelled.replace(respelled.find("[0.5, 1, 0.25]"), 14, "[0.5, 1.0, 0.25]");
    Pipeline b = parsePipeline(respelled, "b.toml");
    std::map<std::string, std::string> hashes = {{"bundle", "xxh128:0"}, {"env", "xxh128:1"}};
    for (const char* id : {"left", "right"}) {
        const PipelineStage& stageA = a.stages[findStage(a, id)];
        const PipelineStage& stageB = b.stages[findStage(b, id)];
        EXPECT_EQ(keyOf(keyIngredients(stageA, hashes)), keyOf(keyIngredients(stageB, hashes))) << id;
    }
}

TEST(Keys, EachIngredientChangesTheKey) {
    Pipeline pipeline = parsePipeline(kDiamond, "diamond.toml");
    PipelineStage stage = pipeline.stages[findStage(pipeline, "left")];
    std::map<std::string, std::string> hashes = {{"bundle", "xxh128:0"}, {"env", "xxh128:1"}};
    std::string base = keyOf(keyIngredients(stage, hashes));
    EXPECT_EQ(base, keyOf(keyIngredients(stage, hashes)));

    std::map<std::string, std::string> otherInput = hashes;
    otherInput["env"] = "xxh128:2";
    EXPECT_NE(base, keyOf(keyIngredients(stage, otherInput)));
    PipelineStage otherParam = stage;
    otherParam.params["rotate-y"] = 91.0;
    EXPECT_NE(base, keyOf(keyIngredients(otherParam, hashes)));
    PipelineStage otherVersion = stage;
    otherVersion.version += 1;
    EXPECT_NE(base, keyOf(keyIngredients(otherVersion, hashes)));
    EXPECT_NE(base, keyOf(keyIngredients(stage, hashes, 0, 2)));
    EXPECT_NE(keyOf(keyIngredients(stage, hashes, 0, 2)), keyOf(keyIngredients(stage, hashes, 1, 2)));
}

TEST(Parse, ShippedPipelinesAreValid) {
    int count = 0;
    for (const auto& item : std::filesystem::directory_iterator(PRT_SOURCE_DIR "/pipelines")) {
        if (item.path().extension() != ".toml") continue;
        EXPECT_NO_THROW(parsePipeline(readFileBytes(item.path().string()), item.path().string())) << item.path();
        ++count;
    }
    EXPECT_GE(count, 2);
}

// The catalogue mirrors the stages' command lines: every flag it passes exists there.
TEST(Catalogue, FlagsExistOnTheStagesCommandLines) {
    for (const StageSpec& spec : stageCatalogue()) {
        std::string help;
        ASSERT_EQ(test::shell(test::kPrt + " " + spec.name + " --help", &help), 0) << spec.name;
        std::vector<std::string> flags;
        for (const PortSpec& port : spec.inputs) flags.push_back(port.flag);
        for (const PortSpec& port : spec.outputs) flags.push_back(port.flag);
        for (const ParamSpec& param : spec.params)
            if (!param.positional) flags.push_back("--" + param.name);
        if (spec.takesThreads) flags.push_back("--threads");
        if (spec.shardable) flags.push_back("--shard");
        for (const std::string& flag : flags) {
            if (flag.empty()) continue;
            bool listed = help.find(flag + " ") != std::string::npos || help.find(flag + ",") != std::string::npos;
            EXPECT_TRUE(listed) << spec.name << " has no " << flag;
        }
    }
    const StageSpec* scene = findStageSpec("scene");
    ASSERT_NE(scene, nullptr);
    EXPECT_EQ(scene->params[0].choices, sceneNames());
}

} // namespace
} // namespace prt
