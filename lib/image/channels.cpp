// Reading named channels of multi-channel images (coefficient textures) through OpenImageIO (image_library.h).
#include "image.h"

#include "core.h"
#include "image_library.h"

#include <algorithm>
#include <filesystem>

namespace prt {

static OpenedImage openImage(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "", "file not found");
    checkExrHeaders(path);
    std::string error;
    OpenedImage input = openImageFile(path, error);
    if (!input.handle) throw Error(path, "", "not a readable image (" + error + ")");
    if (input.deep) throw Error(path, "", "deep image data is not a flat image");
    return input;
}

std::vector<std::string> imageChannelNames(const std::string& path) {
    return openImage(path).channelNames;
}

ImageChannels readImageChannels(const std::string& path, const std::vector<std::string>& names) {
    const OpenedImage spec = openImage(path);
    std::vector<int> channelOf(names.size());
    for (size_t k = 0; k < names.size(); ++k) {
        auto found = std::find(spec.channelNames.begin(), spec.channelNames.end(), names[k]);
        if (found == spec.channelNames.end()) throw Error(path, "channel " + names[k], "is missing");
        channelOf[k] = int(found - spec.channelNames.begin());
    }
    ImageChannels image;
    image.width = spec.width;
    image.height = spec.height;
    if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0 || spec.deep) throw Error(path, "", "image has no flat pixels");
    checkedProduct({uint64_t(spec.width), uint64_t(spec.height), uint64_t(spec.channels)}, "texel values", path, "header");
    size_t pixels = size_t(spec.width) * spec.height;
    std::vector<float> file(pixels * spec.channels);
    std::string error;
    if (!readOpenedPixels(spec, spec.channels, file.data(), error))
        throw Error(path, "pixels", "cannot read (" + error + ")");
    image.values.resize(pixels * names.size());
    for (size_t p = 0; p < pixels; ++p)
        for (size_t k = 0; k < names.size(); ++k)
            image.values[p * names.size() + k] = file[p * spec.channels + channelOf[k]];
    return image;
}

} // namespace prt
