// Writes a small bundle, loads its transfer with the installed runtime and relights it: exit 0 when the
// radiance is the hand-computed one, per vertex and per texel (texels in the bundle, no image library), serially
// and through a job-system hook of its own.
#include <prt/runtime.h> // the umbrella; <prt/relight.h>, <prt/texels.h>, ... one feature each

#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: consumer BUNDLE.glb\n");
        return 2;
    }
    // Three vertices at order 1: transfer[v][0][c] = v + 1, lighting (1, 2, 3), so radiance[v][c] = (v+1)(c+1).
    prt::Bundle bundle;
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.mesh.indices = {0, 1, 2};
    prt::Layer transfer;
    transfer.name = "transfer";
    transfer.domain = "vertex";
    transfer.semantic = "sh_transfer_rgb";
    transfer.shape = {3, 1, 3};
    transfer.data = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    transfer.params = {{"order", 1}};
    bundle.layers.push_back(transfer);
    try {
        prt::writeBundle(argv[1], bundle);
        prt::RelightModel model = prt::loadRelightModel(argv[1]);
        const float lighting[3] = {1, 2, 3};
        float radiance[9];
        prt::relight(model, lighting, 0, model.vertexCount, radiance);
        // The engine's job system: here a counter that runs the tasks in reverse, to show any order will do.
        int hookCalls = 0;
        prt::JobSystem jobs{[](void* context, size_t count, prt::TaskFunction task, void* data) {
                                ++*static_cast<int*>(context);
                                for (size_t i = count; i-- > 0;) task(data, i);
                            },
                            &hookCalls};
        float hooked[9];
        prt::relight(model, lighting, 0, model.vertexCount, hooked, jobs);
        if (hookCalls != 1 || std::memcmp(hooked, radiance, sizeof radiance) != 0) {
            std::fprintf(stderr, "the job hook was called %d times or changed the radiance\n", hookCalls);
            return 1;
        }
        for (int v = 0; v < 3; ++v)
            for (int c = 0; c < 3; ++c)
                if (std::fabs(radiance[v * 3 + c] - float((v + 1) * (c + 1))) > 1e-6f) {
                    std::fprintf(stderr, "radiance[%d][%d] = %g, expected %d\n", v, c, radiance[v * 3 + c],
                                 (v + 1) * (c + 1));
                    return 1;
                }
        // Per-texel transfer stored in the bundle's own buffers: a 2x1 atlas, texel t has transfer t + 1.
        prt::Layer texels;
        texels.name = "texel_transfer";
        texels.domain = "texel";
        texels.semantic = "sh_transfer_rgb";
        texels.shape = {2, 1, 3};
        texels.data = {1, 1, 1, 2, 2, 2};
        texels.params = {{"order", 1}, {"width", 2}, {"height", 1}};
        bundle.layers.push_back(texels);
        prt::TexelRelightModel atlas = prt::texelRelightModel(bundle, "in-memory bundle");
        float texelRadiance[6];
        prt::relight(atlas.rows, lighting, 0, atlas.rows.vertexCount, texelRadiance);
        if (atlas.width != 2 || texelRadiance[5] != 6.0f) {
            std::fprintf(stderr, "texel radiance %g, expected 6\n", texelRadiance[5]);
            return 1;
        }
    } catch (const std::exception& e) { // prt::Error is a std::runtime_error
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    std::printf("consumer: relit %d vertices\n", 3);
    return 0;
}
