// Per-vertex rgb radiance files: .npy for tools, .csv for people and spreadsheets.
#include "compare.h"

#include "core.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string_view>

namespace prt {

namespace {

std::string_view trim(std::string_view text) {
    size_t begin = text.find_first_not_of(" \t\r");
    if (begin == std::string_view::npos) return {};
    return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

// Parses "r,g,b" into rgb; false if the line is not three numbers.
bool parseRow(std::string_view line, float rgb[3]) {
    for (int c = 0; c < 3; ++c) {
        size_t comma = line.find(',');
        if ((c < 2) == (comma == std::string_view::npos)) return false;
        std::string_view field = trim(line.substr(0, comma));
        auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), rgb[c]);
        if (error != std::errc() || end != field.data() + field.size()) return false;
        if (c < 2) line.remove_prefix(comma + 1);
    }
    return true;
}

std::vector<float> readCsv(const std::string& path) {
    std::string text = readFileBytes(path);
    std::vector<float> rgb;
    std::string_view rest = text;
    bool firstLine = true;
    for (size_t lineNumber = 1; !rest.empty(); ++lineNumber) {
        size_t newline = rest.find('\n');
        std::string_view line = trim(rest.substr(0, newline));
        rest.remove_prefix(newline == std::string_view::npos ? rest.size() : newline + 1);
        if (line.empty()) continue;
        float row[3];
        bool parsed = parseRow(line, row);
        // Only the first line may be a header, and only one that starts with a letter: a malformed first data
        // row is still an error.
        bool header = !parsed && firstLine && std::isalpha((unsigned char)line[0]);
        firstLine = false;
        if (header) continue;
        if (!parsed) throw Error(path, "line " + std::to_string(lineNumber), "expected three numbers \"r,g,b\"");
        for (float value : row)
            if (!std::isfinite(value)) throw Error(path, "line " + std::to_string(lineNumber), "value is not finite");
        rgb.insert(rgb.end(), row, row + 3);
    }
    return rgb;
}

std::vector<float> readNpyRows(const std::string& path) {
    std::vector<size_t> shape;
    std::vector<float> rgb = readNpy(path, &shape);
    if (shape.size() != 2 || shape[1] != 3) {
        std::string text;
        for (size_t n : shape) {
            if (!text.empty()) text += ',';
            text += std::to_string(n);
        }
        throw Error(path, "header", "expected shape [N,3], found [" + text + "]");
    }
    for (size_t i = 0; i < rgb.size(); ++i)
        if (!std::isfinite(rgb[i]))
            throw Error(path, "row " + std::to_string(i / 3) + ", channel " + std::to_string(i % 3),
                        "value is not finite");
    return rgb;
}

} // namespace

void writeVertexRadiance(const std::string& path, const std::vector<float>& rgb) {
    std::string extension = fileExtension(path);
    if (rgb.size() % 3 != 0) throw Error(path, "", "internal: radiance is not rgb rows", kExitFailure);
    requireFiniteResult(rgb.data(), rgb.size(), 3, path);
    if (extension == "npy") return writeNpy(path, rgb, {rgb.size() / 3, 3});
    if (extension != "csv") throw Error(path, "", "unknown radiance format (use .npy or .csv)", kExitUsage);
    std::string text = "r,g,b\n";
    char line[64];
    for (size_t i = 0; i < rgb.size(); i += 3) {
        // %.9g is enough digits for any float to read back bit-exact.
        int length = std::snprintf(line, sizeof line, "%.9g,%.9g,%.9g\n", rgb[i], rgb[i + 1], rgb[i + 2]);
        text.append(line, size_t(length));
    }
    writeBytesAtomic(path, text);
}

std::vector<float> readVertexRadiance(const std::string& path) {
    std::string extension = fileExtension(path);
    if (extension == "npy") return readNpyRows(path);
    if (extension == "csv") return readCsv(path);
    throw Error(path, "", "unknown radiance format (use .npy or .csv)");
}

} // namespace prt
