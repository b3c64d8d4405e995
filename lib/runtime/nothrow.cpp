// The no-throw API (prt/nothrow.h): each throwing entry point wrapped so that nothing escapes, every failure a
// status code with the message the exception carried.
#include "runtime.h"

#include <filesystem>
#include <new>
#include <system_error>

namespace prt {

namespace {

// Runs `body`, mapping what it throws: prt::Error to `errorCode` (NotFound when `path` names no file),
// std::bad_alloc to OutOfMemory, anything else to Internal.
template <class Body>
Status guarded(StatusCode errorCode, const std::string* path, Body&& body) noexcept {
    try {
        if (path) {
            std::error_code ec;
            if (!std::filesystem::is_regular_file(*path, ec))
                return {StatusCode::NotFound, *path + ": no such file"};
        }
        body();
        return {};
    } catch (const Error& e) {
        return {errorCode, e.what()};
    } catch (const std::bad_alloc&) {
        return {StatusCode::OutOfMemory, "out of memory"};
    } catch (const std::exception& e) {
        return {StatusCode::Internal, e.what()};
    } catch (...) {
        return {StatusCode::Internal, "unknown exception"};
    }
}

} // namespace

const char* statusName(StatusCode code) noexcept {
    switch (code) {
    case StatusCode::Ok: return "ok";
    case StatusCode::NotFound: return "not found";
    case StatusCode::Corrupt: return "corrupt";
    case StatusCode::InvalidInput: return "invalid input";
    case StatusCode::OutOfMemory: return "out of memory";
    case StatusCode::Internal: return "internal";
    }
    return "internal";
}

Expected<RelightModel> tryLoadRelightModel(const std::string& bundlePath) noexcept {
    RelightModel model;
    Status status = guarded(StatusCode::Corrupt, &bundlePath, [&] { model = loadRelightModel(bundlePath); });
    if (!status) return status;
    return model;
}

Expected<TexelRelightModel> tryLoadTexelRelightModel(const std::string& bundlePath) noexcept {
    TexelRelightModel model;
    Status status =
        guarded(StatusCode::Corrupt, &bundlePath, [&] { model = texelRelightModel(readBundle(bundlePath), bundlePath); });
    if (!status) return status;
    return model;
}

Expected<std::vector<float>> tryReadLightingJson(const std::string& path, int* order) noexcept {
    std::vector<float> lighting;
    Status status = guarded(StatusCode::Corrupt, &path, [&] { lighting = readLightingJson(path, order); });
    if (!status) return status;
    return lighting;
}

Status tryRelight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance,
                  const JobSystem& jobs) noexcept {
    if ((!lighting || !radiance) && begin != end) return {StatusCode::InvalidInput, "relight: null lighting or radiance"};
    return guarded(StatusCode::InvalidInput, nullptr, [&] { relight(model, lighting, begin, end, radiance, jobs); });
}

} // namespace prt
