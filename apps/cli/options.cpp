// The option parsers several subcommands share.
#include "cli.h"

#include "core.h"

#include <cmath>
#include <exception>
#include <sstream>
#include <thread>
#include <vector>

namespace prt::cli {

namespace {

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

} // namespace

std::array<double, 3> parseAlbedo(const std::string& text) {
    std::vector<double> values;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        double value = 0.0;
        try {
            value = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size()) throw usage("--albedo", "'" + text + "' is not R,G,B or a single value");
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

std::array<float, 3> parsePoint(const std::string& text, const char* option) {
    std::vector<float> values;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        double value = 0.0;
        try {
            value = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || !std::isfinite(value) || std::abs(value) > 3e38)
            throw usage(option, "'" + text + "' is not three finite numbers X,Y,Z");
        values.push_back(float(value));
    }
    if (values.size() != 3 || (!text.empty() && text.back() == ','))
        throw usage(option, "'" + text + "' is not three finite numbers X,Y,Z");
    return {values[0], values[1], values[2]};
}

int resolveThreads(int requested) {
    if (requested > 0) return requested;
    unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? int(hw) : 1;
}

} // namespace prt::cli
