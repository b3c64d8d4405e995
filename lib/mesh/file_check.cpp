#include "file_check.h"

#include "core.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace prt::detail {
namespace {

std::string lineName(size_t number) { return "line " + std::to_string(number); }

// Offset of the first byte that cannot be in a text file (NUL, other control bytes), or npos.
size_t firstNonText(std::string_view text) {
    for (size_t i = 0; i < text.size(); ++i) {
        unsigned char c = (unsigned char)text[i];
        if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') return i;
    }
    return std::string_view::npos;
}

// Text formats must be text: a binary or corrupt file would be half-parsed by the readers.
void requireText(std::string_view text, const std::string& path) {
    // UTF-16 and UTF-32 (their byte order marks) are text, but not in the 8-bit encoding the readers parse.
    if (text.starts_with("\xFF\xFE") || text.starts_with("\xFE\xFF") || text.starts_with(std::string_view("\0\0\xFE\xFF", 4)))
        throw Error(path, "byte 0", "UTF-16 or UTF-32 text (its byte order mark): save the file as UTF-8 or ASCII");
    size_t i = firstNonText(text);
    if (i == std::string_view::npos) return;
    char hex[8];
    std::snprintf(hex, sizeof(hex), "0x%02x", (unsigned char)text[i]);
    throw Error(path, "byte " + std::to_string(i), std::string("not a text file (byte ") + hex + ")");
}

// Walks text line by line ('\n', or "\r\n"), numbering lines from 1.
struct LineCursor {
    std::string_view text;
    size_t offset = 0;
    size_t number = 0;

    bool next(std::string_view& line) {
        if (offset >= text.size()) return false;
        size_t end = text.find('\n', offset);
        if (end == std::string_view::npos) end = text.size();
        line = text.substr(offset, end - offset);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        offset = end + 1;
        ++number;
        return true;
    }
};

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v' || c == '\n'; }

// Whitespace-separated tokens of a line, up to a '#' comment when `comments`.
void splitTokens(std::string_view line, std::vector<std::string_view>& tokens, bool comments) {
    tokens.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i])) ++i;
        if (i == line.size() || (comments && line[i] == '#')) break;
        size_t start = i;
        while (i < line.size() && !isSpace(line[i])) ++i;
        tokens.push_back(line.substr(start, i - start));
    }
}

// The whole token as a number; a leading '+' is allowed. "nan" and "inf" parse (and are then refused as
// non-finite); a value beyond float's range reads as infinity, which is what the readers would store.
bool parseReal(std::string_view token, double& value) {
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (token.empty() || end != token.data() + token.size()) return false;
    if (error == std::errc::result_out_of_range) value = std::strtod(std::string(token).c_str(), nullptr); // 0 or HUGE_VAL
    else if (error != std::errc()) return false;
    return true;
}

bool parseInteger(std::string_view token, long long& value) {
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    return error == std::errc() && end == token.data() + token.size() && !token.empty();
}

void requireFiniteFloat(std::string_view token, const std::string& path, const std::string& place, const std::string& what) {
    double value = 0;
    if (!parseReal(token, value)) throw Error(path, place, what + ": '" + std::string(token) + "' is not a number");
    if (!std::isfinite(value) || std::abs(value) > double(std::numeric_limits<float>::max()))
        throw Error(path, place, what + ": non-finite coordinate '" + std::string(token) + "'");
}

// ---- OBJ ----

// A corner's "v/vt/vn" component `which` (0, 1, 2) as a 0-based index, resolving negative (relative) indices
// against the count seen so far; `found` is false when the component is absent.
long long objReference(std::string_view corner, int which, size_t seen, bool& found, const std::string& path,
                       const std::string& place, const std::string& what) {
    for (int k = 0; k < which; ++k) {
        size_t slash = corner.find('/');
        if (slash == std::string_view::npos) {
            found = false;
            return 0;
        }
        corner.remove_prefix(slash + 1);
    }
    corner = corner.substr(0, corner.find('/'));
    found = !corner.empty();
    if (!found) return 0;
    long long value = 0;
    if (!parseInteger(corner, value)) throw Error(path, place, what + ": '" + std::string(corner) + "' is not an index");
    if (value == 0) throw Error(path, place, what + ": index 0 (OBJ indices start at 1)");
    long long index = value > 0 ? value - 1 : (long long)seen + value;
    if (index < 0)
        throw Error(path, place, what + ": relative index " + std::to_string(value) + " points before the first element");
    return index;
}

// The largest texcoord or normal index a face uses, to check once the file's counts are known (OBJ allows
// forward references).
struct LastUse {
    long long index = -1;
    size_t line = 0;
    void note(long long used, size_t lineNumber) {
        if (used > index) index = used, line = lineNumber;
    }
};

} // namespace

bool dropUtf8Bom(std::string& text) {
    if (!text.starts_with("\xEF\xBB\xBF")) return false;
    text.erase(0, 3);
    return true;
}

CheckedFile checkObj(std::string_view text, const std::string& path) {
    requireText(text, path);
    CheckedFile counts;
    counts.vertices = 0;
    size_t texcoords = 0, normals = 0;
    LastUse texcoordUse, normalUse;
    std::vector<std::string_view> tokens;
    std::vector<long long> corners;
    LineCursor lines{text};
    std::string_view line;
    while (lines.next(line)) {
        splitTokens(line, tokens, true);
        if (tokens.empty()) continue;
        std::string_view key = tokens[0];
        std::string place = lineName(lines.number);
        if (key == "v" || key == "vt" || key == "vn") {
            size_t& count = key == "v" ? counts.vertices : key == "vt" ? texcoords : normals;
            size_t needed = key == "vt" ? 2 : 3;
            std::string what = (key == "v" ? "vertex " : key == "vt" ? "texcoord " : "normal ") + std::to_string(count);
            if (tokens.size() < needed + 1)
                throw Error(path, place, what + " has fewer than " + std::to_string(needed) + " numbers (truncated file?)");
            for (size_t k = 1; k <= needed; ++k) requireFiniteFloat(tokens[k], path, place, what);
            ++count;
        } else if (key == "f") {
            std::string what = "face " + std::to_string(counts.faces);
            if (tokens.size() < 4) throw Error(path, place, what + " has fewer than 3 corners (truncated file?)");
            corners.clear();
            for (size_t k = 1; k < tokens.size(); ++k) {
                bool found = false;
                corners.push_back(objReference(tokens[k], 0, counts.vertices, found, path, place, what));
                if (!found) throw Error(path, place, what + ": corner '" + std::string(tokens[k]) + "' names no vertex");
                long long used = objReference(tokens[k], 1, texcoords, found, path, place, what);
                if (found) texcoordUse.note(used, lines.number);
                used = objReference(tokens[k], 2, normals, found, path, place, what);
                if (found) normalUse.note(used, lines.number);
            }
            std::sort(corners.begin(), corners.end());
            if (std::unique(corners.begin(), corners.end()) - corners.begin() < 3) ++counts.facesWithoutTriangle;
            ++counts.faces;
        }
    }
    if (texcoordUse.index >= (long long)texcoords)
        throw Error(path, lineName(texcoordUse.line),
                    "texcoord index " + std::to_string(texcoordUse.index + 1) + " out of range (" + std::to_string(texcoords) +
                        " texcoords)");
    if (normalUse.index >= (long long)normals)
        throw Error(path, lineName(normalUse.line),
                    "normal index " + std::to_string(normalUse.index + 1) + " out of range (" + std::to_string(normals) +
                        " normals)");
    return counts;
}

// ---- OFF ----

namespace {

// OFF text with comments ('#' to the end of a line) blanked, which OpenMesh's OFF reader reads as data. Lines
// keep their numbers.
std::string stripOffComments(std::string_view text) {
    std::string stripped(text);
    bool comment = false;
    for (char& c : stripped) {
        if (c == '\n') comment = false;
        else if (c == '#') comment = true;
        if (comment) c = ' ';
    }
    return stripped;
}

} // namespace

CheckedFile checkOff(std::string_view text, const std::string& path) {
    requireText(text, path);
    LineCursor lines{text};
    std::string_view line;
    std::vector<std::string_view> tokens;
    // OpenMesh's reader needs the keyword alone on the first line and the counts after it.
    if (!lines.next(line)) throw Error(path, "", "empty file");
    splitTokens(line, tokens, true);
    std::string_view keyword = tokens.empty() ? std::string_view() : tokens[0];
    std::string_view prefix = keyword;
    bool hasNormals = false;
    if (prefix.size() >= 3 && prefix.substr(prefix.size() - 3) == "OFF") {
        prefix.remove_suffix(3);
        if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
        if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
        if (!prefix.empty() && prefix[0] == 'N') prefix.remove_prefix(1), hasNormals = true;
    }
    if (keyword.size() < 3 || !prefix.empty())
        throw Error(path, "line 1", "not an OFF file: the first line must be OFF, COFF, NOFF, STOFF or a combination");
    if (tokens.size() > 1 && tokens[1] == "BINARY")
        throw Error(path, "line 1", "binary OFF is not supported; use ascii OFF, PLY or STL");
    if (tokens.size() > 1) throw Error(path, "line 1", "the counts must be on the line after '" + std::string(keyword) + "'");

    auto nextDataLine = [&]() {
        while (lines.next(line)) {
            splitTokens(line, tokens, true);
            if (!tokens.empty()) return true;
        }
        return false;
    };
    if (!nextDataLine()) throw Error(path, "", "file ends before the vertex and face counts (truncated file?)");
    long long declared[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
        if (size_t(k) >= tokens.size() || !parseInteger(tokens[k], declared[k]) || declared[k] < 0)
            throw Error(path, lineName(lines.number), "expected three counts: vertices faces edges");

    // OpenMesh reads the counts and every face token by token, not line by line, so whatever follows the checked
    // tokens on those lines (face colours, or junk) would be read as the next number it wants: a fuzzed "1 0
    // 066666666" made it read a face of 66 M corners, "3 7 0 1 0 0" made it read the vertices from the counts
    // line and the faces out of step. Only the checked tokens reach it; these ranges are blanked.
    std::vector<std::pair<size_t, size_t>> trailing; // [begin, end) of a line after its checked tokens
    auto blankAfter = [&](std::string_view token) {
        trailing.push_back({size_t(token.data() + token.size() - text.data()), size_t(line.data() + line.size() - text.data())});
    };
    blankAfter(tokens[2]);
    checkElementCount(uint64_t(declared[0]), "vertices", path, lineName(lines.number));
    checkElementCount(uint64_t(declared[1]), "faces", path, lineName(lines.number));
    CheckedFile counts;
    counts.vertices = size_t(declared[0]);
    counts.faces = size_t(declared[1]);
    size_t numbers = hasNormals ? 6 : 3;
    for (size_t v = 0; v < counts.vertices; ++v) {
        std::string what = "vertex " + std::to_string(v);
        if (!nextDataLine())
            throw Error(path, what,
                        "file ends before the " + std::to_string(counts.vertices) + " vertices it declares (truncated file?)");
        if (tokens.size() < numbers)
            throw Error(path, lineName(lines.number),
                        what + " has fewer than " + std::to_string(numbers) + " numbers (truncated file?)");
        for (size_t k = 0; k < numbers; ++k) requireFiniteFloat(tokens[k], path, lineName(lines.number), what);
    }
    for (size_t f = 0; f < counts.faces; ++f) {
        std::string what = "face " + std::to_string(f);
        if (!nextDataLine())
            throw Error(path, what,
                        "file ends before the " + std::to_string(counts.faces) + " faces it declares (truncated file?)");
        long long corners = 0;
        if (!parseInteger(tokens[0], corners) || corners < 0)
            throw Error(path, lineName(lines.number), what + ": '" + std::string(tokens[0]) + "' is not a corner count");
        if (tokens.size() < size_t(corners) + 1)
            throw Error(path, lineName(lines.number),
                        what + " lists fewer than its " + std::to_string(corners) + " indices (truncated file?)");
        for (long long k = 1; k <= corners; ++k) {
            long long index = 0;
            if (!parseInteger(tokens[k], index))
                throw Error(path, lineName(lines.number), what + ": '" + std::string(tokens[k]) + "' is not an index");
        }
        blankAfter(tokens[size_t(corners)]);
    }
    counts.readerInput = stripOffComments(text);
    for (auto [begin, end] : trailing) std::fill(counts.readerInput.begin() + long(begin), counts.readerInput.begin() + long(end), ' ');
    return counts;
}

// ---- PLY ----

namespace {

struct PlyType {
    const char* names[2];
    int size;
    bool real;
    bool isSigned;
};
constexpr std::array<PlyType, 8> kPlyTypes = {{
    {{"char", "int8"}, 1, false, true},
    {{"uchar", "uint8"}, 1, false, false},
    {{"short", "int16"}, 2, false, true},
    {{"ushort", "uint16"}, 2, false, false},
    {{"int", "int32"}, 4, false, true},
    {{"uint", "uint32"}, 4, false, false},
    {{"float", "float32"}, 4, true, true},
    {{"double", "float64"}, 8, true, true},
}};

const PlyType* findPlyType(std::string_view name) {
    for (const PlyType& type : kPlyTypes)
        if (name == type.names[0] || name == type.names[1]) return &type;
    return nullptr;
}

struct PlyProperty {
    std::string name;
    const PlyType* type = nullptr;
    const PlyType* countType = nullptr; // list properties only
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// The names OpenMesh's PLY reader accepts for a list's length type.
const char* openMeshCountTypeName(const PlyType& type) {
    if (type.size == 1 && !type.isSigned) return "uchar";
    if (type.size == 2 && !type.isSigned) return "uint16";
    if (type.size == 4 && type.isSigned && !type.real) return "int";
    return nullptr;
}

enum class PlyFormat { ascii, littleEndian, bigEndian };

// A list length stored in binary with the file's byte order.
long long readBinaryCount(const unsigned char* bytes, const PlyType& type, bool bigEndian) {
    uint64_t raw = 0;
    for (int i = 0; i < type.size; ++i) {
        int byte = bigEndian ? i : type.size - 1 - i;
        raw = (raw << 8) | bytes[byte];
    }
    if (type.isSigned && type.size < 8 && (raw >> (type.size * 8 - 1)) & 1) return (long long)raw - (1LL << (type.size * 8));
    return (long long)raw;
}

} // namespace

CheckedFile checkPly(std::string_view bytes, const std::string& path) {
    LineCursor lines{bytes};
    std::string_view line;
    std::vector<std::string_view> tokens;
    if (!lines.next(line) || line != "ply") throw Error(path, "", "not a PLY file (the first line is not 'ply')");
    if (bytes.find("\nend_header") == std::string_view::npos)
        throw Error(path, "header", "ends before end_header (truncated file?)");

    PlyFormat format = PlyFormat::ascii;
    bool sawFormat = false, sawEnd = false;
    std::vector<PlyElement> elements;
    while (!sawEnd && lines.next(line)) {
        splitTokens(line, tokens, false);
        std::string place = "header " + lineName(lines.number);
        if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
        if (tokens[0] == "end_header") {
            sawEnd = true;
        } else if (tokens[0] == "format") {
            if (tokens.size() != 3) throw Error(path, place, "expected 'format FORMAT VERSION'");
            if (tokens[1] == "ascii") format = PlyFormat::ascii;
            else if (tokens[1] == "binary_little_endian") format = PlyFormat::littleEndian;
            else if (tokens[1] == "binary_big_endian") format = PlyFormat::bigEndian;
            else throw Error(path, place, "unknown format '" + std::string(tokens[1]) + "'");
            sawFormat = true;
        } else if (tokens[0] == "element") {
            long long count = 0;
            if (tokens.size() == 3 && parseInteger(tokens[2], count) && count >= 0)
                checkElementCount(uint64_t(count), "'" + std::string(tokens[1]) + "' elements", path, place);
            if (tokens.size() != 3 || !parseInteger(tokens[2], count) || count < 0 || count > UINT32_MAX)
                throw Error(path, place, "expected 'element NAME COUNT' with a count below 2^32");
            elements.push_back({std::string(tokens[1]), uint64_t(count), {}});
        } else if (tokens[0] == "property") {
            if (elements.empty()) throw Error(path, place, "property before any element");
            PlyProperty property;
            if (tokens.size() == 5 && tokens[1] == "list") {
                property.countType = findPlyType(tokens[2]);
                property.type = findPlyType(tokens[3]);
                property.name = std::string(tokens[4]);
                if (property.countType && !openMeshCountTypeName(*property.countType))
                    throw Error(path, place,
                                "list length type '" + std::string(tokens[2]) +
                                    "' is not one OpenMesh reads (uchar, uint16, int)");
            } else if (tokens.size() == 3) {
                property.type = findPlyType(tokens[1]);
                property.name = std::string(tokens[2]);
            }
            if (!property.type || (tokens.size() == 5 && !property.countType))
                throw Error(path, place, "expected 'property TYPE NAME' or 'property list COUNTTYPE TYPE NAME' with PLY types");
            elements.back().properties.push_back(property);
        } else {
            throw Error(path, place, "unknown header keyword '" + std::string(tokens[0]) + "'");
        }
    }
    if (!sawEnd) throw Error(path, "header", "ends before end_header (truncated file?)");
    if (!sawFormat) throw Error(path, "header", "has no format line");

    std::string_view data = bytes.substr(std::min(lines.offset, bytes.size()));
    auto truncated = [&](const PlyElement& element, uint64_t instance) {
        return Error(path, "element '" + element.name + "' " + std::to_string(instance),
                     "data ends before the " + std::to_string(element.count) + " the header declares (truncated file?)");
    };
    if (format == PlyFormat::ascii) {
        requireText(data, path);
        LineCursor dataLines{data};
        std::vector<std::string_view> pending;
        size_t next = 0;
        auto nextToken = [&](std::string_view& token) {
            while (next == pending.size()) {
                if (!dataLines.next(line)) return false;
                splitTokens(line, pending, false);
                next = 0;
            }
            token = pending[next++];
            return true;
        };
        for (const PlyElement& element : elements) {
            for (uint64_t i = 0; i < element.count && !element.properties.empty(); ++i) {
                for (const PlyProperty& property : element.properties) {
                    std::string place = "element '" + element.name + "' " + std::to_string(i);
                    std::string_view token;
                    long long length = 1;
                    if (property.countType) {
                        if (!nextToken(token)) throw truncated(element, i);
                        if (!parseInteger(token, length) || length < 0)
                            throw Error(path, place,
                                        "property '" + property.name + "': '" + std::string(token) + "' is not a list length");
                    }
                    for (long long k = 0; k < length; ++k) {
                        if (!nextToken(token)) throw truncated(element, i);
                        long long integer = 0;
                        if (property.type->real) requireFiniteFloat(token, path, place, "property '" + property.name + "'");
                        else if (!parseInteger(token, integer))
                            throw Error(path, place,
                                        "property '" + property.name + "': '" + std::string(token) + "' is not an integer");
                    }
                }
            }
        }
    } else {
        bool bigEndian = format == PlyFormat::bigEndian;
        const unsigned char* base = reinterpret_cast<const unsigned char*>(data.data());
        size_t offset = 0;
        for (const PlyElement& element : elements) {
            for (uint64_t i = 0; i < element.count && !element.properties.empty(); ++i) {
                for (const PlyProperty& property : element.properties) {
                    long long length = 1;
                    if (property.countType) {
                        if (data.size() - offset < size_t(property.countType->size)) throw truncated(element, i);
                        length = readBinaryCount(base + offset, *property.countType, bigEndian);
                        offset += property.countType->size;
                        if (length < 0)
                            throw Error(path, "element '" + element.name + "' " + std::to_string(i),
                                        "property '" + property.name + "' has a negative list length");
                    }
                    if (uint64_t(length) > (data.size() - offset) / size_t(property.type->size)) throw truncated(element, i);
                    offset += size_t(length) * property.type->size;
                }
            }
        }
    }

    // OpenMesh's header parser reads word by word and loops forever once a read fails; it takes obj_info text
    // for keywords and misplaces binary data after a comment line. It gets the header in its plainest form.
    const char* formatNames[] = {"ascii", "binary_little_endian", "binary_big_endian"};
    std::string header = std::string("ply\nformat ") + formatNames[int(format)] + " 1.0\n";
    CheckedFile counts;
    counts.vertices = 0;
    for (const PlyElement& element : elements) {
        if (element.name == "vertex") counts.vertices = element.count;
        if (element.name == "face") counts.faces = element.count;
        header += "element " + element.name + " " + std::to_string(element.count) + "\n";
        for (const PlyProperty& property : element.properties) {
            header += "property ";
            if (property.countType) header += std::string("list ") + openMeshCountTypeName(*property.countType) + " ";
            header += std::string(property.type->names[0]) + " " + property.name + "\n";
        }
    }
    counts.readerInput = header + "end_header\n" + std::string(data);
    return counts;
}

// ---- STL ----

CheckedFile checkStl(std::string_view bytes, const std::string& path) {
    size_t start = 0;
    while (start < bytes.size() && isSpace(bytes[start])) ++start;
    bool solidHeader = bytes.substr(start, 5) == "solid";
    CheckedFile counts;

    // Binary: an 80-byte header, a triangle count, 50 bytes per triangle. An ascii file is recognised by its
    // "solid" start, unless the size matches the binary layout exactly (some binary headers start with "solid").
    if (bytes.size() >= 84) {
        uint32_t triangles = 0;
        std::memcpy(&triangles, bytes.data() + 80, 4); // little-endian, as the format and this machine are
        uint64_t expected = 84 + 50 * uint64_t(triangles);
        if (bytes.size() == expected || (!solidHeader && bytes.size() > expected)) {
            counts.binary = true;
            counts.faces = triangles;
            for (uint32_t t = 0; t < triangles; ++t) {
                float corner[3][3];
                std::memcpy(corner, bytes.data() + 84 + 50 * size_t(t) + 12, sizeof(corner));
                for (const float* p : corner)
                    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
                        throw Error(path, "triangle " + std::to_string(t), "non-finite coordinate");
                auto same = [](const float* a, const float* b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; };
                if (same(corner[0], corner[1]) || same(corner[1], corner[2]) || same(corner[0], corner[2]))
                    ++counts.facesWithoutTriangle;
            }
            return counts;
        }
        if (!solidHeader || firstNonText(bytes) != std::string_view::npos)
            throw Error(path, "",
                        "binary STL declares " + std::to_string(triangles) + " triangles (" + std::to_string(expected) +
                            " bytes) but the file has " + std::to_string(bytes.size()) + " bytes (truncated file?)");
    }
    if (!solidHeader) throw Error(path, "", "not an STL file: too short for binary STL and no 'solid' keyword");

    requireText(bytes, path);
    LineCursor lines{bytes};
    std::string_view line;
    std::vector<std::string_view> tokens;
    bool inSolid = false, inFacet = false;
    int corners = 0;
    double corner[3][3];
    while (lines.next(line)) {
        splitTokens(line, tokens, false);
        if (tokens.empty()) continue;
        std::string place = lineName(lines.number);
        std::string what = "facet " + std::to_string(counts.faces);
        std::string_view key = tokens[0];
        if (key == "solid") {
            inSolid = true;
        } else if (key == "facet") {
            if (!inSolid || inFacet) throw Error(path, place, "'facet' outside a solid or inside another facet");
            inFacet = true;
            corners = 0;
        } else if (key == "vertex") {
            if (!inFacet || corners == 3) throw Error(path, place, "'vertex' outside a facet or a fourth vertex in " + what);
            if (tokens.size() < 4) throw Error(path, place, what + ": vertex has fewer than 3 numbers (truncated file?)");
            for (int k = 0; k < 3; ++k) {
                requireFiniteFloat(tokens[k + 1], path, place, what);
                parseReal(tokens[k + 1], corner[corners][k]);
                corner[corners][k] = float(corner[corners][k]); // compare as the reader stores them
            }
            ++corners;
        } else if (key == "endfacet") {
            if (!inFacet || corners != 3) throw Error(path, place, what + " has " + std::to_string(corners) + " vertices, not 3");
            auto same = [](const double* a, const double* b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; };
            if (same(corner[0], corner[1]) || same(corner[1], corner[2]) || same(corner[0], corner[2]))
                ++counts.facesWithoutTriangle;
            inFacet = false;
            ++counts.faces;
        } else if (key == "endsolid") {
            if (inFacet) throw Error(path, place, "'endsolid' inside " + what);
            inSolid = false;
        } else if (key != "outer" && key != "endloop") {
            bool lastLineCut = lines.offset > bytes.size(); // no newline after it
            throw Error(path, place,
                        "unknown STL keyword '" + std::string(key) + "'" + (lastLineCut ? " (truncated file?)" : ""));
        }
    }
    if (inSolid || inFacet) throw Error(path, lineName(lines.number), "file ends before 'endsolid' (truncated file?)");
    return counts;
}

} // namespace prt::detail
