#include "core.h"

namespace prt {

static std::string joinMessage(const std::string& file, const std::string& place, const std::string& problem) {
    std::string message;
    for (const std::string* part : {&file, &place, &problem}) {
        if (part->empty()) continue;
        if (!message.empty()) message += ": ";
        message += *part;
    }
    return message;
}

Error::Error(std::string file, std::string place, std::string problem, int exitCode)
    : std::runtime_error(joinMessage(file, place, problem)), file_(std::move(file)), place_(std::move(place)),
      problem_(std::move(problem)), exitCode_(exitCode) {}

std::string fileExtension(const std::string& path) {
    size_t slash = path.find_last_of('/');
    size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
    std::string ext = path.substr(dot + 1);
    for (char& c : ext) c = char(std::tolower((unsigned char)c));
    return ext;
}

} // namespace prt
