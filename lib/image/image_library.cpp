// Finding and loading prt_oiio.so on first use (image_library.h), and prt's side of its C table (oiio_module.h).
#include "image_library.h"

#include "core.h"
#include "oiio_module.h"

#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>

#ifndef PRT_OIIO_BUILD_MODULE
#define PRT_OIIO_BUILD_MODULE ""
#endif
#ifndef PRT_OIIO_INSTALL_MODULE
#define PRT_OIIO_INSTALL_MODULE ""
#endif

namespace prt {

namespace {

constexpr size_t kErrorBytes = 1024;

std::string runningExecutable() {
    char path[4096];
    ssize_t length = readlink("/proc/self/exe", path, sizeof path - 1);
    return length > 0 ? std::string(path, size_t(length)) : std::string();
}

// The module's table, loaded once per process; throws prt::Error naming what is missing.
const PrtOiioModule& module() {
    static std::once_flag once;
    static const PrtOiioModule* table = nullptr;
    static std::string failure;
    std::call_once(once, [] {
        std::vector<std::string> candidates = imageModuleCandidates(runningExecutable());
        std::string path = findImageModule(runningExecutable());
        if (path.empty()) {
            failure = std::string(kImageModuleName) + " (OpenImageIO for prt) was not found; looked for";
            for (const std::string& candidate : candidates) failure += " " + candidate;
            failure += ". Build the prt_oiio target (building prt does) or install prt's runtime component";
            return;
        }
        // Never closed: OpenImageIO keeps threads and plugins for the life of the process.
        void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!library) {
            const char* why = dlerror();
            failure = path + ": cannot load it (" + std::string(why ? why : "unknown error") + ")";
            return;
        }
        auto entry = reinterpret_cast<PrtOiioEntry>(dlsym(library, PRT_OIIO_ENTRY));
        const PrtOiioModule* loaded = entry ? entry() : nullptr;
        if (!loaded) {
            failure = path + ": has no " PRT_OIIO_ENTRY " entry point: not prt's OpenImageIO module";
            return;
        }
        if (loaded->abi != PRT_OIIO_ABI) {
            failure = path + ": interface version " + std::to_string(loaded->abi) + ", this prt needs " +
                      std::to_string(PRT_OIIO_ABI) + ": it belongs to another prt build";
            return;
        }
        table = loaded;
    });
    if (!table) throw Error("", "image module", failure, kExitFailure);
    return *table;
}

OpenedImage openedFrom(void* handle, const PrtImageHeader& header, const char* errorText, std::string& error) {
    OpenedImage image;
    if (!handle) {
        error = errorText;
        return image;
    }
    const PrtOiioModule& table = module();
    image.handle = std::shared_ptr<void>(handle, table.close);
    image.width = header.width;
    image.height = header.height;
    image.channels = header.channels;
    image.deep = header.deep != 0;
    image.cubeEnvironment = header.cubeEnvironment != 0;
    image.unassociatedAlpha = header.unassociatedAlpha != 0;
    for (int c = 0; c < header.channels && c < 4096; ++c) image.channelNames.emplace_back(table.channelName(handle, c));
    return image;
}

bool readPixels(const OpenedImage& image, int channels, bool u8, void* pixels, std::string& error) {
    char text[kErrorBytes] = "";
    if (!image.handle || channels <= 0 || channels > image.channels) {
        error = "no such channels";
        return false;
    }
    if (module().readPixels(image.handle.get(), channels, u8 ? 1 : 0, pixels, text, sizeof text)) return true;
    error = text;
    return false;
}

} // namespace

std::vector<std::string> imageModuleCandidates(const std::string& executable) {
    std::vector<std::string> candidates;
    if (!executable.empty()) {
        std::filesystem::path folder = std::filesystem::path(executable).parent_path();
        candidates.push_back((folder / kImageModuleName).string());
        candidates.push_back((folder.parent_path() / "lib" / "prt" / kImageModuleName).string());
    }
    for (const char* fixed : {PRT_OIIO_BUILD_MODULE, PRT_OIIO_INSTALL_MODULE})
        if (*fixed) candidates.emplace_back(fixed);
    return candidates;
}

std::string findImageModule(const std::string& executable) {
    for (const std::string& candidate : imageModuleCandidates(executable)) {
        std::error_code error;
        if (std::filesystem::is_regular_file(candidate, error)) return candidate;
    }
    return "";
}

OpenedImage openImageFile(const std::string& path, std::string& error) {
    PrtImageHeader header{};
    char text[kErrorBytes] = "";
    void* handle = module().openFile(path.c_str(), &header, text, sizeof text);
    return openedFrom(handle, header, text, error);
}

OpenedImage openImageMemory(const std::string& nameHint, const uint8_t* bytes, size_t size, std::string& error) {
    PrtImageHeader header{};
    char text[kErrorBytes] = "";
    void* handle = module().openMemory(nameHint.c_str(), bytes, size, &header, text, sizeof text);
    return openedFrom(handle, header, text, error);
}

bool readOpenedPixels(const OpenedImage& image, int channels, float* pixels, std::string& error) {
    return readPixels(image, channels, false, pixels, error);
}

bool readOpenedPixels(const OpenedImage& image, int channels, uint8_t* pixels, std::string& error) {
    return readPixels(image, channels, true, pixels, error);
}

ImageWriteResult writeImageFile(const std::string& formatPath, const std::string& tmpPath, int width, int height,
                                const std::vector<std::string>& channelNames, bool u8Pixels, const void* pixels,
                                PixelStorage storage, std::string& error) {
    std::vector<const char*> names;
    for (const std::string& name : channelNames) names.push_back(name.c_str());
    const int stored = storage == PixelStorage::U8 ? 0 : storage == PixelStorage::Half ? 1 : 2;
    char text[kErrorBytes] = "";
    int written = module().write(formatPath.c_str(), tmpPath.c_str(), width, height, int(names.size()), names.data(),
                                 u8Pixels ? 1 : 0, pixels, stored, text, sizeof text);
    if (written == 1) return ImageWriteResult::Written;
    error = text;
    return written == 0 ? ImageWriteResult::NoWriter : ImageWriteResult::Failed;
}

void setImageLibraryThreads(int threads) { module().setThreads(threads); }

std::string imageLibraryVersion() { return module().version; }

} // namespace prt
