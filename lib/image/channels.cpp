// Reading named channels of multi-channel images (coefficient textures) through OpenImageIO.
#include "image.h"

#include "core.h"

#include <OpenImageIO/imageio.h>

#include <filesystem>

namespace prt {

static std::unique_ptr<OIIO::ImageInput> openImage(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "", "file not found");
    checkExrHeaders(path);
    auto input = OIIO::ImageInput::open(path);
    if (!input) throw Error(path, "", "not a readable image (" + OIIO::geterror() + ")");
    if (input->spec().deep) throw Error(path, "", "deep image data is not a flat image");
    return input;
}

std::vector<std::string> imageChannelNames(const std::string& path) {
    return openImage(path)->spec().channelnames;
}

ImageChannels readImageChannels(const std::string& path, const std::vector<std::string>& names) {
    auto input = openImage(path);
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<int> channelOf(names.size());
    for (size_t k = 0; k < names.size(); ++k) {
        channelOf[k] = spec.channelindex(names[k]);
        if (channelOf[k] < 0) throw Error(path, "channel " + names[k], "is missing");
    }
    ImageChannels image;
    image.width = spec.width;
    image.height = spec.height;
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.deep) throw Error(path, "", "image has no flat pixels");
    checkedProduct({uint64_t(spec.width), uint64_t(spec.height), uint64_t(spec.nchannels)}, "texel values", path, "header");
    size_t pixels = size_t(spec.width) * spec.height;
    std::vector<float> file(pixels * spec.nchannels);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, file.data()))
        throw Error(path, "pixels", "cannot read (" + input->geterror() + ")");
    image.values.resize(pixels * names.size());
    for (size_t p = 0; p < pixels; ++p)
        for (size_t k = 0; k < names.size(); ++k)
            image.values[p * names.size() + k] = file[p * spec.nchannels + channelOf[k]];
    return image;
}

} // namespace prt
