// Built with -fno-exceptions: an engine without exceptions loads and relights through <prt/nothrow.h> alone.
// Usage: consumer_nothrow GOOD.glb MISSING.glb CORRUPT.glb; exit 0 when the good bundle relights to the
// hand-computed radiance (consumer's bundle: radiance[v][c] = (v + 1)(c + 1)) and the others give NotFound and
// Corrupt.
#include <prt/nothrow.h>

#include <cstdio>

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: consumer_nothrow GOOD.glb MISSING.glb CORRUPT.glb\n");
        return 2;
    }
    prt::Expected<prt::RelightModel> model = prt::tryLoadRelightModel(argv[1]);
    if (!model) {
        std::fprintf(stderr, "%s: %s\n", prt::statusName(model.status().code), model.status().message.c_str());
        return 1;
    }
    const float lighting[3] = {1, 2, 3};
    float radiance[9];
    prt::Status status = prt::tryRelight(model.value(), lighting, 0, model.value().vertexCount, radiance);
    if (!status || radiance[8] != 9.0f) {
        std::fprintf(stderr, "relight: %s %s, radiance[2][2] = %g\n", prt::statusName(status.code),
                     status.message.c_str(), radiance[8]);
        return 1;
    }
    if (prt::tryRelight(model.value(), lighting, 0, 4, radiance).code != prt::StatusCode::InvalidInput) return 1;
    prt::StatusCode missing = prt::tryLoadRelightModel(argv[2]).status().code;
    prt::StatusCode corrupt = prt::tryLoadRelightModel(argv[3]).status().code;
    if (missing != prt::StatusCode::NotFound || corrupt != prt::StatusCode::Corrupt) {
        std::fprintf(stderr, "missing: %s, corrupt: %s\n", prt::statusName(missing), prt::statusName(corrupt));
        return 1;
    }
    std::printf("consumer_nothrow: relit %u vertices without exceptions\n", model.value().vertexCount);
    return 0;
}
