// The files between the passes of a sharded interreflected transfer: hit records, a shard's rows, and a pass's
// exitant array. One layout for the three (little-endian, as every machine prt builds on):
//   8 bytes "PRTSHARD", uint32 format version (3), uint32 header length H (at most 64 KiB), H bytes of JSON, then
//   the payload, whose every size follows from the header:
//     hits:    uint32 count[rows], uint32 triangle[hit_count], uint32 barycentric[hit_count], uint16 sample[hit_count]
//     rows:    float total[rows][n][3], float direct[rows][n][3], float exitant[rows][n * channels] (not after pass B)
//     exitant: float exitant[vertex_count][n * channels], then char digests[chunks][D]: the exitant section's
//              chunk digests (below; chunks = max(1, ceil(bytes / 1 MiB)), D = the length of hashBytes' text)
// The header names the run (mesh hash, counts, options), and hits and rows their shard, so a file of another run
// is refused by name before its payload is touched; the payload's length must be what the header implies, and
// that is bounded by the element cap, before anything is allocated. The header's "checksums" holds one checksum
// per payload section (counts, triangles, barycentrics, samples; total, direct, exitant): XXH3-128 (hashBytes) of
// the concatenated XXH3-128 digests of the section's consecutive 1 MiB chunks, so it is computed while streaming
// and a reader that skips a section (the gather reads only the exitant rows) checks what it reads. A section is
// checked before any of its values is used: a corrupted byte is refused as such, by file and section. An exitant
// array also stores its chunk digests, whose hash is the header's checksum: a bounce shard checks the table
// against it, then reads only the chunks that hold rows it gathers from and checks each against its digest (the
// gather that wrote the array checked every value finite). Version 3 added the table.
#include "passes.h"

#include "core.h"
#include "json_input.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

namespace prt {

namespace {

constexpr char kMagic[8] = {'P', 'R', 'T', 'S', 'H', 'A', 'R', 'D'};
constexpr uint32_t kFormatVersion = 3;
constexpr size_t kChecksumChunk = 1 << 20;
constexpr uint32_t kMaxHeaderBytes = 64 * 1024;

size_t rowCount(const ShardRun& run) { return run.rowEnd - run.rowBegin; }
uint64_t coefficients(const ShardRun& run) { return uint64_t(run.options.order) * run.options.order; }

// What identifies the run, in the order a mismatch is reported (the mesh first: the likeliest mix-up).
nlohmann::json identity(const ShardRun& run) {
    const TransferOptions& o = run.options;
    return {{"mesh_hash", run.meshHash},
            {"vertex_count", run.vertexCount},
            {"triangle_count", run.triangleCount},
            {"order", o.order},
            {"samples", o.samples},
            {"bounces", o.bounces},
            {"seed", o.seed},
            {"albedo", {double(o.albedo[0]), double(o.albedo[1]), double(o.albedo[2])}},
            {"albedo_override", o.albedoOverride},
            {"channels", run.channels}};
}
const char* const kIdentityOrder[] = {"mesh_hash", "vertex_count", "triangle_count", "order", "samples", "bounces",
                                      "seed", "albedo", "albedo_override", "channels"};

nlohmann::json header(const char* kind, const ShardRun& run, bool withShard) {
    nlohmann::json h = identity(run);
    h["format"] = "prt-transfer-shard";
    h["kind"] = kind;
    if (withShard) {
        h["shard"] = {run.shardIndex, run.shardCount};
        h["row_begin"] = run.rowBegin;
        h["row_end"] = run.rowEnd;
    }
    return h;
}

// A section's checksum (the layout above), fed in pieces of any size.
struct SectionChecksum {
    std::string pending;
    std::string digests;
    void add(const void* data, size_t bytes) {
        const char* at = static_cast<const char*>(data);
        while (bytes > 0) {
            if (pending.empty() && bytes >= kChecksumChunk) { // a whole chunk: hash it where it lies
                digests += hashBytes(at, kChecksumChunk);
                at += kChecksumChunk;
                bytes -= kChecksumChunk;
                continue;
            }
            size_t take = std::min(bytes, kChecksumChunk - pending.size());
            pending.append(at, take);
            at += take;
            bytes -= take;
            if (pending.size() == kChecksumChunk) {
                digests += hashBytes(pending.data(), pending.size());
                pending.clear();
            }
        }
    }
    // The digests of every chunk, the last (partial, or the only one of an empty section) included.
    std::string table() const {
        std::string all = digests;
        if (!pending.empty() || all.empty()) all += hashBytes(pending.data(), pending.size());
        return all;
    }
    std::string value() const {
        const std::string all = table();
        return hashBytes(all.data(), all.size());
    }
};

// Writes the payload section by section, each with its checksum.
struct PayloadWriter {
    std::ofstream& out;
    std::map<std::string, SectionChecksum> sections;
    template <class T>
    void write(const char* section, const T* data, size_t count) {
        out.write(reinterpret_cast<const char*>(data), std::streamsize(count * sizeof(T)));
        sections[section].add(data, count * sizeof(T));
    }
};

// `sections` names the payload's sections, in order; `payload` writes each through the PayloadWriter (and may
// leave one empty). The header is written first with placeholder checksums of the same length, then rewritten.
void writeShardFile(const std::string& path, nlohmann::json head, const std::vector<const char*>& sections,
                    const std::function<void(PayloadWriter&)>& payload) {
    nlohmann::json placeholders = nlohmann::json::object();
    for (const char* section : sections) placeholders[section] = hashBytes("", 0);
    head["checksums"] = placeholders;
    std::string text = head.dump();
    writeFileAtomic(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        uint32_t prefix[2] = {kFormatVersion, uint32_t(text.size())};
        out.write(kMagic, sizeof(kMagic));
        out.write(reinterpret_cast<const char*>(prefix), sizeof(prefix));
        out.write(text.data(), std::streamsize(text.size()));
        PayloadWriter writer{out, {}};
        payload(writer);
        for (const char* section : sections) head["checksums"][section] = writer.sections[section].value();
        std::string final = head.dump();
        if (final.size() != text.size()) throw Error(path, "header", "checksums changed the header's length", kExitFailure);
        out.seekp(sizeof(kMagic) + sizeof(prefix));
        out.write(final.data(), std::streamsize(final.size()));
        out.flush();
        if (!out) throw Error(path, "", "cannot write the shard file", kExitOutput);
    });
}

// An opened shard file whose header matched: the stream stands at the payload.
struct Reader {
    std::string path;
    std::ifstream in;
    nlohmann::json head;
    uint64_t payloadBytes = 0;
    std::map<std::string, SectionChecksum> sections;

    [[noreturn]] void fail(const std::string& place, const std::string& problem) const {
        throw Error(path, place, problem, kExitInput);
    }
    uint64_t count(const char* key) const {
        const nlohmann::json* value = head.contains(key) ? &head[key] : nullptr;
        if (!value || !value->is_number_unsigned()) fail("header", std::string("has no valid '") + key + "'");
        return value->get<uint64_t>();
    }
    // Reads `count` values of payload section `section` (in one or more calls), adding them to its checksum.
    template <class T>
    void read(T* data, uint64_t count, const char* section) {
        in.read(reinterpret_cast<char*>(data), std::streamsize(count * sizeof(T)));
        if (!in) fail(section, "cannot be read (the file changed while it was read?)");
        sections[section].add(data, count * sizeof(T));
    }
    // Reads `bytes` at the stream's position without adding them to a checksum.
    void readRaw(void* data, uint64_t bytes, const char* section) {
        in.read(static_cast<char*>(data), std::streamsize(bytes));
        if (!in) fail(section, "cannot be read (the file changed while it was read?)");
    }
    // The header's checksum of `section`.
    std::string checksum(const char* section) const {
        const nlohmann::json& checksums = head.value("checksums", nlohmann::json());
        if (!checksums.is_object() || !checksums.contains(section) || !checksums[section].is_string())
            fail("header", std::string("has no checksum for the '") + section + "' section");
        return checksums[section].get<std::string>();
    }
    // Once the whole section is read: refuses it unless it matches the header's checksum.
    void verify(const char* section) {
        if (checksum(section) != sections[section].value())
            fail(section, "does not match its checksum: the file is corrupt");
    }
    void readFinite(float* data, uint64_t count, const char* section) {
        read(data, count, section);
        verify(section);
        for (uint64_t i = 0; i < count; ++i)
            if (!std::isfinite(data[i])) fail(section, "value " + std::to_string(i) + " is not finite");
    }
    void skip(uint64_t bytes) { in.seekg(std::streamoff(bytes), std::ios::cur); }
};

// A header value quoted in a message, cut short (the header is untrusted).
std::string describe(const nlohmann::json& value) {
    if (!value.is_string()) return jsonExcerpt(value);
    const std::string& text = value.get_ref<const std::string&>();
    return text.size() > 80 ? text.substr(0, 80) + "..." : text;
}

// Opens `path`, checks the prefix, the kind and the run's identity (and the shard, when withShard).
Reader openShardFile(const std::string& path, const char* kind, const char* what, const ShardRun& run,
                     bool withShard) {
    Reader reader;
    reader.path = path;
    std::error_code error;
    uint64_t size = std::filesystem::file_size(path, error);
    reader.in.open(path, std::ios::binary);
    if (error || !reader.in) throw Error(path, "", std::string("cannot read ") + what + " (missing?)", kExitInput);
    char magic[8];
    uint32_t prefix[2] = {0, 0};
    if (size < sizeof(magic) + sizeof(prefix)) reader.fail("", std::string("is too short to be ") + what);
    reader.read(magic, sizeof(magic), "prefix");
    reader.read(prefix, 2, "prefix");
    if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
        reader.fail("", std::string("is not a prt shard file (expected ") + what + ")");
    if (prefix[0] != kFormatVersion)
        reader.fail("", "has shard format version " + std::to_string(prefix[0]) + "; this prt reads version " +
                            std::to_string(kFormatVersion));
    uint64_t headerBytes = prefix[1];
    if (headerBytes > kMaxHeaderBytes || headerBytes > size - 16)
        reader.fail("header", "claims " + std::to_string(headerBytes) + " bytes, more than the file or 64 KiB");
    std::string text(headerBytes, '\0');
    reader.read(text.data(), headerBytes, "header");
    checkJsonShape(text, path, "header", kMaxHeaderBytes); // nesting bounded before the parse
    reader.head = nlohmann::json::parse(text, nullptr, false);
    nlohmann::json& head = reader.head;
    if (!head.is_object() || jsonString(head, "format", path, "header") != "prt-transfer-shard")
        reader.fail("header", "is not a prt transfer shard header");
    if (jsonString(head, "kind", path, "header") != kind)
        reader.fail("header", "holds '" + describe(head["kind"]) + "', not " + what);
    nlohmann::json expected = identity(run);
    for (const char* key : kIdentityOrder) {
        if (!head.contains(key)) reader.fail("header", std::string("has no '") + key + "'");
        if (head[key] == expected[key]) continue;
        if (std::string(key) == "mesh_hash")
            reader.fail("header", "was written for another mesh (" + describe(head[key]) + "; this run's mesh is " +
                                      describe(expected[key]) + ")");
        reader.fail("header", std::string("was written for ") + key + " " + describe(head[key]) + ", this run has " +
                                  describe(expected[key]));
    }
    if (withShard) {
        nlohmann::json shard = {run.shardIndex, run.shardCount};
        if (head.value("shard", nlohmann::json()) != shard)
            reader.fail("header", "belongs to shard " + describe(head.value("shard", nlohmann::json())) +
                                      " [index, count], this job is shard " + shard.dump());
        if (reader.count("row_begin") != run.rowBegin || reader.count("row_end") != run.rowEnd)
            reader.fail("header", "rows do not match the shard's [" + std::to_string(run.rowBegin) + ", " +
                                      std::to_string(run.rowEnd) + ")");
    }
    reader.payloadBytes = size - 16 - headerBytes;
    return reader;
}

// Checks that the payload holds exactly `bytes` (the sum of sections the header implies).
void expectPayload(const Reader& reader, uint64_t bytes) {
    if (reader.payloadBytes != bytes)
        reader.fail("payload", "holds " + std::to_string(reader.payloadBytes) + " bytes; its header implies " +
                                   std::to_string(bytes) + " (truncated or padded)");
}

int readPass(const Reader& reader, int expected) {
    uint64_t pass = reader.count("pass");
    if (pass > uint64_t(std::numeric_limits<int>::max())) reader.fail("header", "pass " + std::to_string(pass) + " is out of range");
    if (expected >= 0 && pass != uint64_t(expected))
        reader.fail("header", "holds pass " + std::to_string(pass) + ", this job needs pass " + std::to_string(expected));
    return int(pass);
}

} // namespace

namespace passes {

void writeHitRecords(const std::string& path, const ShardRun& run, const std::vector<HitBlock>& blocks) {
    nlohmann::json head = header("hits", run, true);
    uint64_t hits = 0;
    for (const HitBlock& block : blocks) hits += block.triangle.size();
    head["hit_count"] = hits;
    writeShardFile(path, head, {"counts", "triangles", "barycentrics", "samples"}, [&](PayloadWriter& out) {
        std::vector<uint32_t> counts;
        for (const HitBlock& block : blocks) {
            counts.resize(block.end.size());
            for (size_t i = 0; i < block.end.size(); ++i) counts[i] = block.end[i] - (i ? block.end[i - 1] : 0);
            out.write("counts", counts.data(), counts.size());
        }
        for (const HitBlock& block : blocks) out.write("triangles", block.triangle.data(), block.triangle.size());
        for (const HitBlock& block : blocks) out.write("barycentrics", block.barycentric.data(), block.barycentric.size());
        for (const HitBlock& block : blocks) out.write("samples", block.sample.data(), block.sample.size());
    });
}

std::vector<HitBlock> readHitRecords(const std::string& path, const ShardRun& run) {
    Reader reader = openShardFile(path, "hits", "hit records", run, true);
    const size_t rows = rowCount(run);
    uint64_t hits = reader.count("hit_count");
    checkElementCount(hits, "hit records", path, "header");
    checkElementCount(rows, "vertex rows", path, "header");
    expectPayload(reader, uint64_t(rows) * 4 + hits * 10);

    // Read section by section straight into the blocks, so the records are held once.
    std::vector<HitBlock> blocks(hitBlockCount(rows));
    std::vector<uint32_t> counts(rows);
    reader.read(counts.data(), rows, "counts");
    reader.verify("counts");
    const uint64_t samples = uint64_t(run.options.samples);
    uint64_t sum = 0;
    for (size_t b = 0; b < blocks.size(); ++b) {
        HitBlock& block = blocks[b];
        uint32_t end = 0;
        for (size_t v = b * rays::kBlockVertices; v < std::min(rows, (b + 1) * rays::kBlockVertices); ++v) {
            if (counts[v] > samples)
                reader.fail("hit counts", "vertex " + std::to_string(run.rowBegin + v) + " claims " +
                                              std::to_string(counts[v]) + " hits of " + std::to_string(samples) + " rays");
            end += counts[v];
            block.end.push_back(end);
        }
        sum += end;
    }
    if (sum != hits)
        reader.fail("hit counts", "add up to " + std::to_string(sum) + ", the header says " + std::to_string(hits));
    counts = {};
    for (HitBlock& block : blocks) {
        block.triangle.resize(block.end.empty() ? 0 : block.end.back());
        reader.read(block.triangle.data(), block.triangle.size(), "triangles");
    }
    reader.verify("triangles");
    for (HitBlock& block : blocks)
        for (uint32_t t : block.triangle)
            if (t >= run.triangleCount) reader.fail("triangles", "triangle " + std::to_string(t) + " is not in the mesh");
    for (HitBlock& block : blocks) {
        block.barycentric.resize(block.triangle.size());
        reader.read(block.barycentric.data(), block.barycentric.size(), "barycentrics");
    }
    reader.verify("barycentrics");
    for (HitBlock& block : blocks)
        for (uint32_t uv : block.barycentric) // each rounded on its own, so their sum may pass 65535 by one
            if ((uv & 0xFFFFu) + (uv >> 16) > 65536u) reader.fail("barycentrics", "u + v exceeds 1");
    for (HitBlock& block : blocks) {
        block.sample.resize(block.triangle.size());
        reader.read(block.sample.data(), block.sample.size(), "samples");
    }
    reader.verify("samples");
    for (HitBlock& block : blocks) {
        // The direct pass records a vertex's hits in ascending sample order.
        for (size_t i = 0, h = 0; i < block.end.size(); ++i)
            for (size_t first = h; h < block.end[i]; ++h)
                if (block.sample[h] >= samples || (h > first && block.sample[h] <= block.sample[h - 1]))
                    reader.fail("samples", "a vertex's sample indices are not ascending below " + std::to_string(samples));
    }
    return blocks;
}

std::vector<float> readExitant(const std::string& path, const ShardRun& run, int pass,
                               const std::vector<uint8_t>& needed) {
    if (needed.size() != run.vertexCount)
        throw std::logic_error("readExitant: needs one flag per vertex of the run");
    Reader reader = openShardFile(path, "exitant", "an exitant array", run, false);
    readPass(reader, pass);
    const uint64_t rowFloats = coefficients(run) * uint64_t(run.channels);
    const uint64_t floats = checkedProduct({run.vertexCount, rowFloats}, "exitant values", path, "header");
    const uint64_t chunkFloats = kChecksumChunk / 4;
    const uint64_t chunks = std::max<uint64_t>(1, (floats + chunkFloats - 1) / chunkFloats);
    const size_t digestLength = hashBytes("", 0).size();
    expectPayload(reader, floats * 4 + chunks * digestLength);
    // The digest table first, checked against the header: then each chunk read can be checked on its own.
    const std::streamoff start = reader.in.tellg();
    std::string table(chunks * digestLength, '\0');
    reader.in.seekg(start + std::streamoff(floats * 4));
    reader.readRaw(table.data(), table.size(), "digests");
    if (hashBytes(table.data(), table.size()) != reader.checksum("exitant"))
        reader.fail("digests", "do not match the exitant section's checksum: the file is corrupt");
    // The chunks that hold a marked row, in order.
    std::vector<uint8_t> wanted(chunks, 0);
    uint64_t kept = 0;
    for (uint64_t v = 0; v < run.vertexCount; ++v) {
        if (!needed[v]) continue;
        ++kept;
        for (uint64_t c = v * rowFloats / chunkFloats; c <= ((v + 1) * rowFloats - 1) / chunkFloats; ++c) wanted[c] = 1;
    }
    std::vector<float> exitant(kept * rowFloats);
    if (kept == 0) return exitant;
    std::vector<float> piece(std::min(chunkFloats, floats));
    float* out = exitant.data();
    for (uint64_t c = 0; c < chunks; ++c) {
        if (!wanted[c]) continue;
        const uint64_t first = c * chunkFloats, count = std::min(chunkFloats, floats - first);
        reader.in.seekg(start + std::streamoff(first * 4));
        reader.readRaw(piece.data(), count * 4, "exitant");
        if (hashBytes(piece.data(), count * 4) != table.substr(c * digestLength, digestLength))
            reader.fail("exitant", "chunk " + std::to_string(c) + " does not match its checksum: the file is corrupt");
        for (uint64_t i = 0; i < count; ++i)
            if (!std::isfinite(piece[i]))
                reader.fail("exitant", "value " + std::to_string(first + i) + " is not finite");
        for (uint64_t f = first; f < first + count;) { // row by row: the part of row f / rowFloats in this chunk
            const uint64_t end = std::min(first + count, (f / rowFloats + 1) * rowFloats);
            if (needed[f / rowFloats]) out = std::copy(piece.data() + (f - first), piece.data() + (end - first), out);
            f = end;
        }
    }
    return exitant;
}

} // namespace passes

void writeShardRows(const std::string& path, const ShardRun& run, const ShardRows& rows) {
    nlohmann::json head = header("rows", run, true);
    head.update({{"pass", rows.pass}, {"rays", rows.rays}, {"hits", rows.hits}, {"back_face_hits", rows.backFaceHits},
                 {"ray_offset", double(rows.rayOffset)}, {"has_exitant", rows.pass < run.options.bounces}});
    writeShardFile(path, head, {"total", "direct", "exitant"}, [&](PayloadWriter& out) {
        out.write("total", rows.total.data(), rows.total.size());
        out.write("direct", rows.direct.data(), rows.direct.size());
        out.write("exitant", rows.exitant.data(), rows.exitant.size());
    });
}

namespace {

// Opens shard rows of `run`'s shard and pass `pass`, checks the header and the payload's length, and fills the
// header's fields of `rows`; the stream stands at the "total" section. hasExitant says whether the rows hold an
// exitant section (all passes but the last), exitantFloats its length.
Reader openShardRows(const std::string& path, const ShardRun& run, int pass, ShardRows& rows, uint64_t& totalFloats,
                     uint64_t& exitantFloats, bool& hasExitantRows) {
    Reader reader = openShardFile(path, "rows", "shard rows", run, true);
    rows.pass = readPass(reader, pass);
    rows.rowBegin = run.rowBegin;
    rows.rowEnd = run.rowEnd;
    rows.rays = reader.count("rays");
    rows.hits = reader.count("hits");
    rows.backFaceHits = reader.count("back_face_hits");
    const nlohmann::json& offset = reader.head.value("ray_offset", nlohmann::json());
    const nlohmann::json& hasExitant = reader.head.value("has_exitant", nlohmann::json());
    if (!offset.is_number() || !hasExitant.is_boolean()) reader.fail("header", "has no valid 'ray_offset' or 'has_exitant'");
    rows.rayOffset = jsonFloat(reader.head, "ray_offset", path, "header");
    uint64_t n = coefficients(run);
    totalFloats = checkedProduct({rowCount(run), n, 3}, "row values", path, "header");
    exitantFloats = hasExitant.get<bool>() ? checkedProduct({rowCount(run), n, uint64_t(run.channels)},
                                                            "exitant values", path, "header") : 0;
    expectPayload(reader, (2 * totalFloats + exitantFloats) * 4);
    hasExitantRows = hasExitant.get<bool>();
    return reader;
}

} // namespace

ShardRows readShardRows(const std::string& path, const ShardRun& run, int pass) {
    ShardRows rows;
    uint64_t totalFloats = 0, exitantFloats = 0;
    bool hasExitant = false;
    Reader reader = openShardRows(path, run, pass, rows, totalFloats, exitantFloats, hasExitant);
    rows.total.resize(totalFloats);
    rows.direct.resize(totalFloats);
    reader.readFinite(rows.total.data(), totalFloats, "total");
    reader.readFinite(rows.direct.data(), totalFloats, "direct");
    return rows;
}

// Streams: the shards' headers are checked first (which shard each file is, the pass), then each shard's exitant
// section is copied into the output in shard order, 1 MiB at a time, and checked at its end against its checksum,
// then for finite values, as readShardRows checks its sections (a failure removes the unfinished output:
// writeShardFile is atomic). Memory: 1 MiB and the headers, whatever the vertex count.
int gatherExitant(const std::vector<std::string>& parts, const ShardRun& run, const std::string& output) {
    if (parts.size() != size_t(run.shardCount) || parts.empty())
        throw Error("", "--gather", "needs the " + std::to_string(run.shardCount) + " shards of one pass, got " +
                                        std::to_string(parts.size()), kExitUsage);
    checkedProduct({run.vertexCount, coefficients(run), uint64_t(run.channels)}, "exitant values", "", "gather");
    std::vector<int> seen(parts.size(), -1); // seen[I]: the file of shard I
    int pass = -1;
    for (size_t s = 0; s < parts.size(); ++s) {
        Reader peek = openShardFile(parts[s], "rows", "shard rows", run, false);
        const nlohmann::json claimed = peek.head.value("shard", nlohmann::json());
        if (!claimed.is_array() || claimed.size() != 2 || claimed[1] != run.shardCount || !claimed[0].is_number_unsigned() ||
            claimed[0].get<uint64_t>() >= uint64_t(run.shardCount))
            peek.fail("header", "is not one of " + std::to_string(run.shardCount) + " shards (shard " +
                                    describe(claimed) + ")");
        int index = claimed[0].get<int>();
        if (seen[index] >= 0)
            peek.fail("header", "is shard " + std::to_string(index) + " again (also " + parts[seen[index]] + ")");
        seen[index] = int(s);
        if (pass < 0) pass = readPass(peek, -1);
    }
    // Every index seen once among shardCount files: the ranges tile [0, vertexCount) in index order.
    nlohmann::json head = header("exitant", run, false);
    head["pass"] = pass;
    writeShardFile(output, head, {"exitant"}, [&](PayloadWriter& out) {
        std::vector<float> piece(kChecksumChunk / sizeof(float));
        for (int index = 0; index < run.shardCount; ++index) {
            const std::string& path = parts[seen[index]];
            ShardRun shard = run;
            shard.shardIndex = index;
            RowRange range = shardRows(run.vertexCount, index, run.shardCount);
            shard.rowBegin = range.begin;
            shard.rowEnd = range.end;
            ShardRows rows;
            uint64_t totalFloats = 0, exitantFloats = 0;
            bool hasExitant = false;
            Reader reader = openShardRows(path, shard, pass, rows, totalFloats, exitantFloats, hasExitant);
            if (!hasExitant) reader.fail("header", "holds no exitant rows (the last pass writes none)");
            reader.skip(2 * totalFloats * 4);
            uint64_t infinite = exitantFloats; // the first value that is not finite, reported once the checksum held
            for (uint64_t at = 0; at < exitantFloats; at += piece.size()) {
                size_t count = size_t(std::min<uint64_t>(piece.size(), exitantFloats - at));
                reader.read(piece.data(), count, "exitant");
                for (size_t i = 0; i < count && infinite == exitantFloats; ++i)
                    if (!std::isfinite(piece[i])) infinite = at + i;
                out.write("exitant", piece.data(), count);
            }
            reader.verify("exitant");
            if (infinite < exitantFloats) reader.fail("exitant", "value " + std::to_string(infinite) + " is not finite");
        }
        // The chunk digests after the section, so that a bounce reads and checks only the chunks it needs.
        const std::string table = out.sections["exitant"].table();
        out.out.write(table.data(), std::streamsize(table.size()));
    });
    return pass;
}

} // namespace prt
