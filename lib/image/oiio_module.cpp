// prt_oiio.so: OpenImageIO behind the C table of oiio_module.h. The only code of prt that includes or links
// OpenImageIO; it allocates nothing on prt's behalf (the caller checks sizes and passes its buffers).
#include "oiio_module.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/oiioversion.h>

#include <cstring>
#include <memory>
#include <string>

namespace {

struct OpenedImage {
    std::unique_ptr<OIIO::Filesystem::IOMemReader> memory; // the proxy an in-memory image reads through
    std::unique_ptr<OIIO::ImageInput> input;
};

void copyError(const std::string& message, char* error, size_t errorSize) {
    if (!error || errorSize == 0) return;
    size_t length = std::min(message.size(), errorSize - 1);
    std::memcpy(error, message.data(), length);
    error[length] = '\0';
}

void fillHeader(const OIIO::ImageSpec& spec, PrtImageHeader* header) {
    header->width = spec.width;
    header->height = spec.height;
    header->channels = spec.nchannels;
    header->deep = spec.deep ? 1 : 0;
    header->cubeEnvironment = spec.get_string_attribute("textureformat") == "CubeFace Environment" ? 1 : 0;
    header->unassociatedAlpha = spec.get_int_attribute("oiio:UnassociatedAlpha", 0) != 0 ? 1 : 0;
}

void* opened(std::unique_ptr<OpenedImage> image, PrtImageHeader* header, char* error, size_t errorSize) {
    if (!image->input) {
        copyError(OIIO::geterror(), error, errorSize);
        return nullptr;
    }
    fillHeader(image->input->spec(), header);
    return image.release();
}

void setThreads(int threads) { OIIO::attribute("threads", threads); }

void* openFile(const char* path, PrtImageHeader* header, char* error, size_t errorSize) {
    auto image = std::make_unique<OpenedImage>();
    image->input = OIIO::ImageInput::open(path);
    return opened(std::move(image), header, error, errorSize);
}

void* openMemory(const char* nameHint, const unsigned char* bytes, size_t size, PrtImageHeader* header, char* error,
                 size_t errorSize) {
    auto image = std::make_unique<OpenedImage>();
    image->memory = std::make_unique<OIIO::Filesystem::IOMemReader>(const_cast<unsigned char*>(bytes), size);
    image->input = OIIO::ImageInput::open(nameHint, nullptr, image->memory.get());
    return opened(std::move(image), header, error, errorSize);
}

const char* channelName(void* image, int channel) {
    const OIIO::ImageSpec& spec = static_cast<OpenedImage*>(image)->input->spec();
    return channel >= 0 && channel < int(spec.channelnames.size()) ? spec.channelnames[size_t(channel)].c_str() : "";
}

int readPixels(void* handle, int channels, int u8, void* pixels, char* error, size_t errorSize) {
    OIIO::ImageInput& input = *static_cast<OpenedImage*>(handle)->input;
    if (input.read_image(0, 0, 0, channels, u8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT, pixels)) return 1;
    copyError(input.geterror(), error, errorSize);
    return 0;
}

void close(void* image) { delete static_cast<OpenedImage*>(image); }

int write(const char* formatPath, const char* tmpPath, int width, int height, int channels,
          const char* const* channelNames, int u8Pixels, const void* pixels, int storage, char* error,
          size_t errorSize) {
    // The temporary name hides the extension, so the format comes from the final path.
    auto output = OIIO::ImageOutput::create(formatPath);
    if (!output) {
        copyError(OIIO::geterror(), error, errorSize);
        return 0;
    }
    bool exr = std::string(output->format_name()) == "openexr";
    OIIO::TypeDesc stored = storage == 0 ? OIIO::TypeDesc::UINT8 : storage == 1 ? OIIO::TypeDesc::HALF
                                                                                : OIIO::TypeDesc::FLOAT;
    OIIO::ImageSpec spec(width, height, channels, stored);
    spec.channelnames.assign(channelNames, channelNames + channels);
    spec.alpha_channel = -1; // named channels, none of them alpha, whatever their count
    if (exr) {
        spec.attribute("compression", "zip");
        // OIIO would stamp the current time as capDate: a fixed one keeps same pixels, same bytes. (PNG gets
        // no time chunk unless asked.)
        spec.attribute("DateTime", "1970:01:01 00:00:00");
    }
    OIIO::TypeDesc given = u8Pixels ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT;
    if (!output->open(tmpPath, spec) || !output->write_image(given, pixels) || !output->close()) {
        copyError(output->geterror(), error, errorSize);
        return -1;
    }
    return 1;
}

const PrtOiioModule kModule = {PRT_OIIO_ABI, OIIO_VERSION_STRING, setThreads, openFile, openMemory, channelName,
                               readPixels,   close,               write};

} // namespace

extern "C" __attribute__((visibility("default"))) const PrtOiioModule* prt_oiio_module(void) { return &kModule; }
