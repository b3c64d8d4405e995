// Pipeline files: TOML through toml++, validated key by key so that every error names the file, the line and the
// key. The format is documented in docs/pipelines.md.
#include "pipeline.h"

#include "core.h"
#include "utf8.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>

namespace prt {

namespace {

struct Context {
    std::string file;

    [[noreturn]] void fail(int line, const std::string& key, const std::string& problem) const {
        throw Error(file, "line " + std::to_string(line) + (key.empty() ? "" : ", " + key), problem, kExitInput);
    }
};

int lineOf(const toml::node& node) { return int(node.source().begin.line); }
int lineOf(const toml::key& key) { return int(key.source().begin.line); }

std::string typeName(const toml::node& node) {
    switch (node.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a float";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date or time";
    }
}

size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
            diagonal = above;
        }
    }
    return row[b.size()];
}

std::string joinNames(const std::vector<std::string>& names) {
    std::string list;
    for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
    return list;
}

// "unknown key 'sample' of a 'transfer' stage; did you mean 'samples'? (known: ...)"
std::string unknownKey(const std::string& what, const std::string& key, const std::vector<std::string>& known,
                       const std::string& owner = "") {
    std::string message = "unknown " + what + " '" + key + "'" + (owner.empty() ? "" : " " + owner);
    auto closest = std::min_element(known.begin(), known.end(), [&](const std::string& a, const std::string& b) {
        return editDistance(key, a) < editDistance(key, b);
    });
    if (closest != known.end() && editDistance(key, *closest) <= 2) message += "; did you mean '" + *closest + "'?";
    return message + " (known: " + (known.empty() ? "none" : joinNames(known)) + ")";
}

bool isName(const std::string& text) {
    return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
        return std::isalnum((unsigned char)c) || c == '_' || c == '-';
    });
}

const toml::table& requireTable(const Context& context, const toml::node& node, const std::string& key) {
    if (!node.is_table()) context.fail(lineOf(node), key, "must be a table, got " + typeName(node));
    return *node.as_table();
}

std::string requireString(const Context& context, const toml::node& node, const std::string& key) {
    if (!node.is_string()) context.fail(lineOf(node), key, "must be a string, got " + typeName(node));
    std::string value = node.as_string()->get();
    if (value.empty()) context.fail(lineOf(node), key, "must not be empty");
    return value;
}

// A file path of the pipeline (an input's or an output's): a string naming a file, so no NUL byte (the system
// would cut the name there) and, for an output, no folder (a trailing '/', or a folder that exists).
std::string requirePath(const Context& context, const toml::node& node, const std::string& key, bool output) {
    std::string path = requireString(context, node, key);
    if (path.find('\0') != std::string::npos)
        context.fail(lineOf(node), key, "holds a NUL byte, which no file name can");
    std::error_code error;
    if (output && (path.back() == '/' || std::filesystem::is_directory(path, error)))
        context.fail(lineOf(node), key, "'" + path + "' is a folder: an output path names the file to write");
    return path;
}

std::string formatNumber(double value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", value);
    return text;
}

std::string rangeText(const ParamSpec& spec) {
    return "[" + formatNumber(spec.min) + ", " + formatNumber(spec.max) + "]";
}

double requireNumber(const Context& context, const toml::node& node, const std::string& key, const ParamSpec& spec) {
    if (!node.is_number()) context.fail(lineOf(node), key, "must be a number, got " + typeName(node));
    double value = node.is_integer() ? double(node.as_integer()->get()) : node.as_floating_point()->get();
    if (!(value >= spec.min && value <= spec.max))
        context.fail(lineOf(node), key, "must lie in " + rangeText(spec) + ", got " + formatNumber(value));
    return value;
}

// A parameter as canonical JSON: the same value always hashes the same, however the file spells it (90 or 90.0).
nlohmann::json parseParam(const Context& context, const toml::node& node, const std::string& key,
                          const ParamSpec& spec) {
    switch (spec.type) {
    case ParamType::Integer: {
        if (!node.is_integer()) context.fail(lineOf(node), key, "must be an integer, got " + typeName(node));
        int64_t value = node.as_integer()->get();
        // Compared as integers: as doubles, 2^53 + 1 would round onto a bound of 2^53 and pass.
        auto integer = [](double b) {
            return b >= 9.2e18 ? std::numeric_limits<int64_t>::max()
                               : b <= -9.2e18 ? std::numeric_limits<int64_t>::min() : int64_t(b);
        };
        if (value < integer(std::ceil(spec.min)) || value > integer(std::floor(spec.max)))
            context.fail(lineOf(node), key, "must be an integer in " + rangeText(spec) + ", got " + std::to_string(value));
        return value;
    }
    case ParamType::Number: return requireNumber(context, node, key, spec);
    case ParamType::Boolean:
        if (!node.is_boolean()) context.fail(lineOf(node), key, "must be true or false, got " + typeName(node));
        return node.as_boolean()->get();
    case ParamType::String: {
        std::string value = requireString(context, node, key);
        if (!spec.choices.empty() && std::find(spec.choices.begin(), spec.choices.end(), value) == spec.choices.end()) {
            context.fail(lineOf(node), key, "'" + value + "' is not one of: " + joinNames(spec.choices));
        }
        return value;
    }
    case ParamType::Color: {
        const toml::array* array = node.as_array();
        if (!array || array->size() != 3)
            context.fail(lineOf(node), key, "must be an array of 3 numbers [r, g, b], got " +
                                                (array ? "an array of " + std::to_string(array->size()) : typeName(node)));
        nlohmann::json rgb = nlohmann::json::array();
        for (const toml::node& channel : *array) rgb.push_back(requireNumber(context, channel, key, spec));
        return rgb;
    }
    }
    return nullptr;
}

bool feeds(FileKind output, FileKind input) {
    return output == input || (output == FileKind::Bundle && input == FileKind::Mesh);
}

void parseInputs(const Context& context, const toml::table& table, Pipeline& pipeline) {
    const std::vector<std::string> kinds = {"mesh", "env", "bundle", "radiance", "sh"};
    for (const auto& [key, node] : table) {
        std::string name(key.str());
        std::string where = "inputs." + name;
        if (!isName(name)) context.fail(lineOf(key), where, "input names use letters, digits, '_' and '-'");
        const toml::table& entry = requireTable(context, node, where);
        if (entry.size() != 1)
            context.fail(lineOf(node), where, "must hold exactly one of mesh, env, bundle, radiance, sh, as in "
                                              "{ mesh = \"path\" }");
        auto [kindKey, pathNode] = *entry.begin(); // a proxy of references
        std::string kindName(kindKey.str());
        if (std::find(kinds.begin(), kinds.end(), kindName) == kinds.end())
            context.fail(lineOf(kindKey), where + "." + kindName, unknownKey("input kind", kindName, kinds));
        PipelineInput input;
        input.name = name;
        input.kind = kindName == "mesh"       ? FileKind::Mesh
                     : kindName == "env"      ? FileKind::Env
                     : kindName == "bundle"   ? FileKind::Bundle
                     : kindName == "radiance" ? FileKind::Radiance
                                              : FileKind::Sh;
        input.path = requirePath(context, pathNode, where + "." + kindName, false);
        input.line = lineOf(pathNode);
        pipeline.inputs.push_back(input);
    }
}

const PipelineInput* findInput(const Pipeline& pipeline, const std::string& name) {
    for (const PipelineInput& input : pipeline.inputs)
        if (input.name == name) return &input;
    return nullptr;
}

const PipelineStage* findStageById(const std::vector<PipelineStage>& stages, const std::string& id) {
    for (const PipelineStage& stage : stages)
        if (stage.id == id) return &stage;
    return nullptr;
}

std::vector<std::string> portNames(const std::vector<PortSpec>& ports) {
    std::vector<std::string> names;
    for (const PortSpec& port : ports) names.push_back(port.name);
    return names;
}

const PortSpec* findPort(const std::vector<PortSpec>& ports, const std::string& name) {
    for (const PortSpec& port : ports)
        if (port.name == name) return &port;
    return nullptr;
}

// Resolves "stage" or "stage.port" (a stage's first output) or "input" to what it names; fails with `where`.
StageInput resolveReference(const Context& context, const Pipeline& pipeline, const std::vector<PipelineStage>& stages,
                            const std::string& reference, int line, const std::string& where, FileKind* kind) {
    StageInput wire;
    wire.line = line;
    size_t dot = reference.find('.');
    wire.source = reference.substr(0, dot);
    std::string port = dot == std::string::npos ? "" : reference.substr(dot + 1);
    if (const PipelineInput* input = findInput(pipeline, wire.source)) {
        if (!port.empty())
            context.fail(line, where, "'" + wire.source + "' is a pipeline input, which has no output '" + port + "'");
        *kind = input->kind;
        return wire;
    }
    const PipelineStage* source = findStageById(stages, wire.source);
    if (!source) {
        std::vector<std::string> names;
        for (const PipelineInput& input : pipeline.inputs) names.push_back(input.name);
        for (const PipelineStage& stage : stages) names.push_back(stage.id);
        context.fail(line, where, "missing input: " + unknownKey("input or stage", wire.source, names));
    }
    const PortSpec* output = port.empty() ? &source->spec->outputs.front() : findPort(source->spec->outputs, port);
    if (!output)
        context.fail(line, where, unknownKey("output", port, portNames(source->spec->outputs),
                                             "of stage '" + source->id + "' (" + source->spec->name + ")"));
    wire.sourcePort = output->name;
    *kind = output->kind;
    return wire;
}

PipelineStage parseStageHeader(const Context& context, const std::string& id, const toml::node& node) {
    std::string where = "stages." + id;
    if (!isName(id)) context.fail(lineOf(node), where, "stage ids use letters, digits, '_' and '-'");
    const toml::table& table = requireTable(context, node, where);
    PipelineStage stage;
    stage.id = id;
    stage.line = lineOf(node);
    const toml::node* run = table.get("run");
    if (!run) context.fail(stage.line, where, "missing key 'run': the stage to run (one of the prt stages)");
    std::string name = requireString(context, *run, where + ".run");
    stage.spec = findStageSpec(name);
    if (!stage.spec) {
        std::vector<std::string> names;
        for (const StageSpec& spec : stageCatalogue()) names.push_back(spec.name);
        context.fail(lineOf(*run), where + ".run", unknownKey("stage", name, names));
    }
    stage.version = stage.spec->version;
    return stage;
}

// The stage's parameters and shard count: every key but `run` and `inputs`.
void parseStageParams(const Context& context, const toml::table& table, PipelineStage& stage) {
    const StageSpec& spec = *stage.spec;
    std::string where = "stages." + stage.id;
    std::vector<std::string> known = {"run", "inputs", "shards"};
    for (const ParamSpec& param : spec.params) known.push_back(param.name);
    stage.params = nlohmann::json::object();
    for (const auto& [key, node] : table) {
        std::string name(key.str());
        std::string keyPath = where + "." + name;
        if (name == "run") continue;
        if (name == "shards") {
            if (!node.is_integer()) context.fail(lineOf(node), keyPath, "must be an integer, got " + typeName(node));
            int64_t shards = node.as_integer()->get();
            if (shards < 1 || shards > 4096)
                context.fail(lineOf(node), keyPath, "must be an integer in [1, 4096], got " + std::to_string(shards));
            if (shards > 1 && !spec.shardable) {
                std::vector<std::string> shardable;
                for (const StageSpec& other : stageCatalogue())
                    if (other.shardable) shardable.push_back(other.name);
                context.fail(lineOf(node), keyPath, "stage '" + spec.name + "' cannot be sharded (these can: " +
                                                        joinNames(shardable) + ")");
            }
            stage.shards = int(shards);
            continue;
        }
        if (name == "inputs") continue;
        auto param = std::find_if(spec.params.begin(), spec.params.end(), [&](const ParamSpec& p) { return p.name == name; });
        if (param == spec.params.end())
            context.fail(lineOf(key), keyPath, unknownKey("key", name, known, "of a '" + spec.name + "' stage"));
        stage.params[name] = parseParam(context, node, keyPath, *param);
    }
    for (const ParamSpec& param : spec.params)
        if (param.required && !stage.params.contains(param.name))
            context.fail(stage.line, where, "missing parameter '" + param.name + "' of stage '" + spec.name + "'");
    if (spec.paramsRefusal) {
        std::string refusal = spec.paramsRefusal(stage.params);
        if (!refusal.empty()) context.fail(stage.line, where, refusal);
    }
    if (stage.shards > 1) {
        std::string refusal = spec.shardRefusal ? spec.shardRefusal(stage.params) : "";
        if (!refusal.empty()) context.fail(lineOf(*table.get("shards")), where + ".shards", refusal);
    }
}

// The stage's `inputs` table: which pipeline input or stage output feeds each of its ports.
void parseStageWiring(const Context& context, const Pipeline& pipeline, const std::vector<PipelineStage>& stages,
                      const toml::table& table, PipelineStage& stage) {
    const StageSpec& spec = *stage.spec;
    std::string where = "stages." + stage.id;
    const toml::node* inputsNode = table.get("inputs");
    if (!inputsNode && !spec.inputs.empty())
        context.fail(stage.line, where, "missing key 'inputs': wire " + joinNames(portNames(spec.inputs)));
    std::map<std::string, StageInput> wired;
    if (inputsNode) {
        const toml::table& inputs = requireTable(context, *inputsNode, where + ".inputs");
        for (const auto& [key, node] : inputs) {
            std::string port(key.str());
            std::string keyPath = where + ".inputs." + port;
            const PortSpec* portSpec = findPort(spec.inputs, port);
            if (!portSpec)
                context.fail(lineOf(key), keyPath, unknownKey("input", port, portNames(spec.inputs), "of stage '" + spec.name + "'"));
            std::string reference = requireString(context, node, keyPath);
            FileKind kind;
            StageInput wire = resolveReference(context, pipeline, stages, reference, lineOf(node), keyPath, &kind);
            wire.port = port;
            if (wire.source == stage.id) context.fail(lineOf(node), keyPath, "cycle: stage '" + stage.id + "' feeds itself");
            if (!feeds(kind, portSpec->kind))
                context.fail(lineOf(node), keyPath, "type error: input '" + port + "' of '" + spec.name +
                                                        "' takes kind " + fileKindName(portSpec->kind) + ", but '" +
                                                        reference + "' is kind " + fileKindName(kind));
            wired[port] = wire;
        }
    }
    for (const PortSpec& port : spec.inputs) {
        auto found = wired.find(port.name);
        if (found != wired.end()) stage.inputs.push_back(found->second);
        else if (!port.optional)
            context.fail(inputsNode ? lineOf(*inputsNode) : stage.line, where + ".inputs",
                         "missing input '" + port.name + "' (a " + fileKindName(port.kind) + ")");
    }
    if (!spec.exactlyOneInput.empty()) {
        std::string names;
        int count = 0;
        for (const std::string& port : spec.exactlyOneInput) {
            count += int(wired.count(port));
            names += (names.empty() ? "" : " or ") + port;
        }
        bool allowedPair = false;
        for (const auto& [first, second] : spec.alsoTogether) {
            allowedPair = allowedPair || (count == 2 && wired.count(first) && wired.count(second));
            names += " (or " + first + " with " + second + ")";
        }
        if (count != 1 && !allowedPair)
            context.fail(inputsNode ? lineOf(*inputsNode) : stage.line, where + ".inputs",
                         "needs exactly one of " + names + ", got " + std::to_string(count));
    }
}

// Depth-first topological order; ties keep the file's order. Fails naming the stages of a cycle.
std::vector<PipelineStage> sortStages(const Context& context, std::vector<PipelineStage> stages) {
    std::sort(stages.begin(), stages.end(), [](const PipelineStage& a, const PipelineStage& b) { return a.line < b.line; });
    std::vector<int> state(stages.size(), 0); // 0 new, 1 on the path, 2 done
    std::vector<size_t> path, order;
    std::function<void(size_t)> visit = [&](size_t i) {
        if (state[i] == 2) return;
        if (state[i] == 1) {
            std::string cycle = stages[i].id;
            for (auto it = std::find(path.begin(), path.end(), i) + 1; it != path.end(); ++it) cycle += " -> " + stages[*it].id;
            context.fail(stages[i].line, "stages." + stages[i].id, "cycle: " + cycle + " -> " + stages[i].id);
        }
        state[i] = 1;
        path.push_back(i);
        for (const StageInput& input : stages[i].inputs)
            for (size_t j = 0; j < stages.size(); ++j)
                if (stages[j].id == input.source) visit(j);
        path.pop_back();
        state[i] = 2;
        order.push_back(i);
    };
    for (size_t i = 0; i < stages.size(); ++i) visit(i);
    std::vector<PipelineStage> sorted;
    for (size_t i : order) sorted.push_back(std::move(stages[i]));
    return sorted;
}

void parseOutputs(const Context& context, const toml::table& table, Pipeline& pipeline) {
    for (const auto& [key, node] : table) {
        std::string name(key.str());
        std::string where = "outputs." + name;
        const toml::table& entry = requireTable(context, node, where);
        for (const auto& [field, value] : entry)
            if (field.str() != "from" && field.str() != "path")
                context.fail(lineOf(field), where + "." + std::string(field.str()),
                             unknownKey("key", std::string(field.str()), {"from", "path"}, "of an output"));
        const toml::node* from = entry.get("from");
        const toml::node* path = entry.get("path");
        if (!from) context.fail(lineOf(node), where, "missing key 'from': the stage (or stage.output) it copies");
        if (!path) context.fail(lineOf(node), where, "missing key 'path': where the run writes it");
        PipelineOutput output;
        output.name = name;
        output.line = lineOf(node);
        output.path = requirePath(context, *path, where + ".path", true);
        std::string reference = requireString(context, *from, where + ".from");
        FileKind kind;
        StageInput wire = resolveReference(context, pipeline, pipeline.stages, reference, lineOf(*from), where + ".from", &kind);
        if (wire.sourcePort.empty())
            context.fail(lineOf(*from), where + ".from", "'" + reference + "' is a pipeline input, not a stage product");
        output.stage = wire.source;
        output.port = wire.sourcePort;
        std::string normalized = std::filesystem::path(output.path).lexically_normal().string();
        for (const PipelineOutput& other : pipeline.outputs)
            if (std::filesystem::path(other.path).lexically_normal().string() == normalized)
                context.fail(lineOf(*path), where + ".path", "duplicate output: '" + output.path +
                                                                 "' is also written by output '" + other.name +
                                                                 "' (line " + std::to_string(other.line) + ")");
        for (const PipelineInput& input : pipeline.inputs)
            if (std::filesystem::path(input.path).lexically_normal().string() == normalized)
                context.fail(lineOf(*path), where + ".path", "would overwrite input '" + input.name + "'");
        pipeline.outputs.push_back(output);
    }
}

// toml++ nests one table per part of a dotted key (`a.b.c = 1`, `[a.b.c]`, also inside inline tables) and
// recurses over them, unbounded by its TOML_MAX_NESTED_VALUES: 100,000 parts overflow the stack. This scan, one
// pass without recursion, refuses a key of more than kMaxTomlKeyParts parts first. Strings (basic, literal,
// multi-line) and comments are skipped; dots in values (numbers) are not counted.
constexpr int kMaxTomlKeyParts = 64;
void checkTomlKeyParts(std::string_view text, const Context& context) {
    int line = 1, parts = 1;
    bool key = true;         // reading a key: at a line's start, in a header, after '{' or ',' in an inline table
    std::vector<char> open;  // '[' arrays and '{' inline tables of the value being read
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '\n') {
            ++line;
            if (open.empty()) key = true, parts = 1;
        } else if (c == '#') {
            while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
        } else if (c == '"' || c == '\'') {
            const bool triple = text.substr(i, 3) == std::string(3, c);
            const size_t start = i + (triple ? 3 : 1);
            size_t end = start;
            for (; end < text.size(); ++end) {
                if (c == '"' && text[end] == '\\') { ++end; continue; }
                if (text[end] == '\n') ++line;
                if (text[end] == c && (!triple || text.substr(end, 3) == std::string(3, c))) break;
            }
            i = end + (triple ? 2 : 0);
        } else if (key) {
            if (c == '.' && ++parts > kMaxTomlKeyParts)
                context.fail(line, "", "a dotted key of more than " + std::to_string(kMaxTomlKeyParts) + " parts");
            if (c == '=') key = false, parts = 1;
            if (c == '}' && !open.empty()) open.pop_back(), key = false; // an empty inline table
        } else if (c == '[' || c == '{') {
            open.push_back(c);
            if (c == '{') key = true, parts = 1;
        } else if ((c == ']' || c == '}') && !open.empty()) {
            open.pop_back();
        } else if (c == ',' && !open.empty() && open.back() == '{') {
            key = true, parts = 1;
        }
    }
}

} // namespace

Pipeline parsePipeline(std::string_view text, const std::string& file) {
    Context context{file};
    checkTomlKeyParts(text, context); // before toml++ recurses over the key's tables
    toml::table root;
    try {
        root = toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        context.fail(int(e.source().begin.line), "", "TOML syntax: " + std::string(e.description()));
    }
    const std::vector<std::string> sections = {"pipeline", "inputs", "stages", "outputs"};
    for (const auto& [key, node] : root)
        if (std::find(sections.begin(), sections.end(), key.str()) == sections.end())
            context.fail(lineOf(key), std::string(key.str()), unknownKey("section", std::string(key.str()), sections));

    Pipeline pipeline;
    pipeline.file = file;
    pipeline.name = std::filesystem::path(file).stem().string();
    if (const toml::node* node = root.get("pipeline")) {
        const toml::table& table = requireTable(context, *node, "pipeline");
        for (const auto& [key, value] : table) {
            std::string name(key.str());
            if (name == "name") {
                pipeline.name = requireString(context, value, "pipeline.name");
                if (!isName(pipeline.name)) context.fail(lineOf(value), "pipeline.name", "use letters, digits, '_' and '-'");
            } else if (name == "description") {
                pipeline.description = requireString(context, value, "pipeline.description");
            } else {
                context.fail(lineOf(key), "pipeline." + name, unknownKey("key", name, {"name", "description"}));
            }
        }
    }
    // The name goes into Slurm job names and scripts, so the default (the file stem) obeys the same rule.
    if (!isName(pipeline.name)) {
        context.fail(1, "pipeline.name", "the file stem '" + printableBytes(pipeline.name) +
                                             "' is the default name but is not one (letters, digits, '_' and '-'): "
                                             "rename the file or set name in a [pipeline] table");
    }
    if (const toml::node* node = root.get("inputs")) parseInputs(context, requireTable(context, *node, "inputs"), pipeline);

    const toml::node* stagesNode = root.get("stages");
    if (!stagesNode || !stagesNode->is_table() || stagesNode->as_table()->empty())
        context.fail(stagesNode ? lineOf(*stagesNode) : 1, "stages", "the pipeline has no stages ([stages.NAME] tables)");
    const toml::table& stagesTable = *stagesNode->as_table();
    std::vector<PipelineStage> stages;
    for (const auto& [key, node] : stagesTable) {
        std::string id(key.str());
        if (const PipelineInput* input = findInput(pipeline, id))
            context.fail(lineOf(key), "stages." + id, "duplicate name: '" + id + "' is also an input (line " +
                                                          std::to_string(input->line) + ")");
        stages.push_back(parseStageHeader(context, id, node));
    }
    // Wiring comes once every stage is known, as a stage may name one defined further down.
    for (PipelineStage& stage : stages) {
        const toml::table& table = *stagesTable.get(stage.id)->as_table();
        parseStageParams(context, table, stage);
        parseStageWiring(context, pipeline, stages, table, stage);
    }
    pipeline.stages = sortStages(context, std::move(stages));

    const toml::node* outputsNode = root.get("outputs");
    if (!outputsNode || !outputsNode->is_table() || outputsNode->as_table()->empty())
        context.fail(outputsNode ? lineOf(*outputsNode) : 1, "outputs",
                     "the pipeline declares no outputs: name the bundle it produces in [outputs]");
    parseOutputs(context, *outputsNode->as_table(), pipeline);

    for (const PipelineInput& input : pipeline.inputs) {
        bool used = std::any_of(pipeline.stages.begin(), pipeline.stages.end(), [&](const PipelineStage& stage) {
            return std::any_of(stage.inputs.begin(), stage.inputs.end(), [&](const StageInput& w) { return w.source == input.name; });
        });
        if (!used) context.fail(input.line, "inputs." + input.name, "input '" + input.name + "' feeds no stage");
    }
    return pipeline;
}

Pipeline loadPipeline(const std::string& file) {
    Pipeline pipeline = parsePipeline(readFileBytes(file), file);
    for (const PipelineInput& input : pipeline.inputs) {
        std::error_code error;
        if (std::filesystem::is_directory(input.path, error))
            throw Error(file, "line " + std::to_string(input.line) + ", inputs." + input.name,
                        "input '" + input.path + "' is a folder, not a file", kExitInput);
        if (std::filesystem::exists(input.path, error) && !std::filesystem::is_regular_file(input.path, error))
            throw Error(file, "line " + std::to_string(input.line) + ", inputs." + input.name,
                        "input '" + input.path + "' is not a regular file (a device, a FIFO or a socket)", kExitInput);
        if (!std::filesystem::is_regular_file(input.path, error))
            throw Error(file, "line " + std::to_string(input.line) + ", inputs." + input.name,
                        "missing input file '" + input.path + "' (relative paths start at the current directory " +
                            std::filesystem::current_path().string() + ")",
                        kExitInput);
    }
    // What the parse compared by name, compared again by the file each path leads to (absolute paths, links, "..").
    namespace fs = std::filesystem;
    for (size_t i = 0; i < pipeline.outputs.size(); ++i) {
        const PipelineOutput& output = pipeline.outputs[i];
        const std::string place = "line " + std::to_string(output.line) + ", outputs." + output.name + ".path";
        std::error_code error;
        const fs::path resolved = fs::weakly_canonical(fs::absolute(output.path), error);
        for (size_t j = 0; j < i; ++j)
            if (fs::weakly_canonical(fs::absolute(pipeline.outputs[j].path), error) == resolved)
                throw Error(file, place, "'" + output.path + "' is the file output '" + pipeline.outputs[j].name +
                                             "' writes too (line " + std::to_string(pipeline.outputs[j].line) + ")",
                            kExitInput);
        if (!fs::exists(output.path, error)) continue;
        if (fs::equivalent(output.path, file, error))
            throw Error(file, place, "'" + output.path + "' is this pipeline file", kExitInput);
        for (const PipelineInput& input : pipeline.inputs)
            if (fs::equivalent(output.path, input.path, error))
                throw Error(file, place, "'" + output.path + "' is the file of input '" + input.name +
                                             "' (line " + std::to_string(input.line) + "): the run would overwrite it",
                            kExitInput);
    }
    return pipeline;
}

void checkOutputsInside(const Pipeline& pipeline) {
    namespace fs = std::filesystem;
    std::error_code error;
    auto resolved = [&](const fs::path& path) { return fs::weakly_canonical(fs::absolute(path), error); };
    const fs::path current = resolved(fs::current_path(error));
    const fs::path fileFolder = resolved(fs::path(pipeline.file).parent_path().empty() ? fs::path(".")
                                                                                        : fs::path(pipeline.file).parent_path());
    for (const PipelineOutput& output : pipeline.outputs) {
        // An output is never a folder (parsePipeline), so "strictly inside" is "inside".
        if (!resolvedInside(output.path, current.string()).empty() ||
            !resolvedInside(output.path, fileFolder.string()).empty())
            continue;
        const fs::path target = resolved(output.path);
        throw Error(pipeline.file, "line " + std::to_string(output.line) + ", outputs." + output.name + ".path",
                    "'" + output.path + "' resolves to " + target.string() + ", outside the current directory (" +
                        current.string() + ") and the pipeline's folder (" + fileFolder.string() +
                        "); outputs stay inside them unless `prt run --allow-outputs-anywhere`",
                    kExitInput);
    }
}

size_t findStage(const Pipeline& pipeline, const std::string& id) {
    std::string names;
    for (size_t i = 0; i < pipeline.stages.size(); ++i) {
        if (pipeline.stages[i].id == id) return i;
        names += (names.empty() ? "" : ", ") + pipeline.stages[i].id;
    }
    throw Error(pipeline.file, "", "no stage '" + id + "' (stages: " + names + ")", kExitUsage);
}

} // namespace prt
