// The option parsers several subcommands share.
#include "cli.h"

#include "core.h"
#include "raycast.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <exception>
#include <sstream>
#include <thread>
#include <vector>

namespace prt::cli {

namespace {

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

// The items of a comma-separated list, as std::getline splits it (a trailing comma adds no item).
std::vector<std::string> commaItems(const std::string& text) {
    std::vector<std::string> items;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) items.push_back(item);
    return items;
}

// One item as a double (std::stod): false unless the whole item is the number.
bool parseItem(const std::string& item, double& value) {
    size_t used = 0;
    try {
        value = std::stod(item, &used);
    } catch (const std::exception&) {
        return false;
    }
    return used != 0 && used == item.size();
}

// Parses exactly `count` comma-separated finite numbers.
std::vector<float> parseNumbers(const std::string& text, size_t count, const char* option) {
    std::vector<float> numbers;
    const char* cursor = text.data();
    const char* end = text.data() + text.size();
    for (;;) {
        const char* comma = std::find(cursor, end, ',');
        float value;
        auto [parsed, error] = std::from_chars(cursor, comma, value);
        if (error != std::errc() || parsed != comma || !std::isfinite(value))
            throw Error("", option, "\"" + text + "\" is not " + std::to_string(count) + " comma-separated numbers",
                        kExitUsage);
        numbers.push_back(value);
        if (comma == end) break;
        cursor = comma + 1;
    }
    if (numbers.size() != count)
        throw Error("", option, "expected " + std::to_string(count) + " numbers, got " + std::to_string(numbers.size()),
                    kExitUsage);
    return numbers;
}

} // namespace

void parsePinholeCamera(const std::string& size, const char* sizeOption, const std::string& view,
                        PinholeCamera& camera) {
    std::vector<float> wh = parseNumbers(size, 2, sizeOption);
    std::vector<float> numbers = parseNumbers(view, 10, "--camera");
    if (wh[0] < 1 || wh[1] < 1 || wh[0] != std::floor(wh[0]) || wh[1] != std::floor(wh[1]) || wh[0] > 65536 ||
        wh[1] > 65536)
        throw Error("", sizeOption, "width and height must be positive integers up to 65536", kExitUsage);
    if (!(numbers[9] > 0.0f && numbers[9] < 180.0f)) throw Error("", "--camera", "FOVY must lie in (0, 180)", kExitUsage);
    // The image's RGBA floats, refused by the element cap before anything is allocated for them.
    checkCommandLineSize({uint64_t(wh[0]), uint64_t(wh[1]), 4}, "image values (W x H x RGBA)", sizeOption);
    camera.width = int(wh[0]);
    camera.height = int(wh[1]);
    std::copy(numbers.begin(), numbers.begin() + 3, camera.eye.begin());
    std::copy(numbers.begin() + 3, numbers.begin() + 6, camera.target.begin());
    std::copy(numbers.begin() + 6, numbers.begin() + 9, camera.up.begin());
    camera.fovyDegrees = numbers[9];
    pinholeRays(camera); // throws for eye == target or up along the view
}

std::array<double, 3> parseAlbedo(const std::string& text) {
    std::vector<double> values;
    for (const std::string& item : commaItems(text)) {
        double value = 0.0;
        if (!parseItem(item, value)) throw usage("--albedo", "'" + text + "' is not R,G,B or a single value");
        if (!(value >= 0.0 && value <= 1.0)) throw usage("--albedo", "components must lie in [0, 1]");
        values.push_back(value);
    }
    if (values.size() == 1) return {values[0], values[0], values[0]};
    if (values.size() != 3) throw usage("--albedo", "'" + text + "' is not R,G,B or a single value");
    return {values[0], values[1], values[2]};
}

void parseShard(const std::string& text, int& index, int& count) {
    char slash = 0, rest = 0;
    std::istringstream in(text);
    if (!(in >> index >> slash >> count) || slash != '/' || (in >> rest) || count < 1 || index < 0 || index >= count)
        throw usage("--shard", "'" + text + "' is not I/N with 0 <= I < N");
}

namespace {

std::vector<double> parseNumberList(const std::string& text, const std::string& flag, const std::string& form) {
    std::vector<double> values;
    for (const std::string& item : commaItems(text)) {
        double value = 0.0;
        if (!parseItem(item, value) || !std::isfinite(value)) throw usage(flag, "'" + text + "' is not " + form);
        values.push_back(value);
    }
    return values;
}

} // namespace

void parsePhongBrdf(const std::string& text, double& exponent, double& ks) {
    const std::string form = "phong:EXPONENT,KS";
    if (text.rfind("phong:", 0) != 0) throw usage("--brdf", "'" + text + "' is not " + form + " (the only model)");
    std::vector<double> values = parseNumberList(text.substr(6), "--brdf", form);
    if (values.size() != 2) throw usage("--brdf", "'" + text + "' is not " + form);
    if (!(values[0] > 0.0)) throw usage("--brdf", "the Phong exponent must be > 0, got " + text.substr(6));
    if (!(values[1] >= 0.0 && values[1] <= 1.0)) throw usage("--brdf", "KS must lie in [0, 1]");
    exponent = values[0];
    ks = values[1];
}

CLI::Option* outputFile(CLI::Option* option) { return option->type_name(kOutputTypeName); }

void optionNeeds(CLI::App* command, const char* option, const char* needed) {
    command->get_option(option)->needs(command->get_option(needed));
}

std::array<float, 3> parsePoint(const std::string& text, const char* option) {
    std::vector<float> values;
    for (const std::string& item : commaItems(text)) {
        double value = 0.0;
        if (!parseItem(item, value) || !std::isfinite(value) || std::abs(value) > 3e38)
            throw usage(option, "'" + text + "' is not three finite numbers X,Y,Z");
        values.push_back(float(value));
    }
    if (values.size() != 3 || (!text.empty() && text.back() == ','))
        throw usage(option, "'" + text + "' is not three finite numbers X,Y,Z");
    return {values[0], values[1], values[2]};
}

uint64_t checkCommandLineSize(const std::vector<uint64_t>& factors, const std::string& what, const char* option) {
    try {
        return checkedProduct(factors, what, "", option);
    } catch (const Error& e) {
        throw Error("", option, e.problem(), kExitUsage);
    }
}

int resolveThreads(int requested) {
    if (requested < 0) throw Error("", "--threads", "must be >= 0 (0: all cores)", kExitUsage);
    if (requested > 0) return requested;
    unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? int(hw) : 1;
}

} // namespace prt::cli
