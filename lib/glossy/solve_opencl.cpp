// The batched solver: lm_kernel.cl on the first OpenCL device (PoCL's CPU device here), one work item per
// problem. The context, queue and the program for each lobe count and cache size are created once per process.
#include "glossy.h"
#include "glossy_internal.h"
#include "lm_kernel.h"

#include "core.h"

#include <CL/cl.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

namespace prt::glossy {

namespace {

constexpr size_t kLocalSize = 16; // every work group full, so every problem runs the same code path
constexpr const char* kNoPlatform =
    "no OpenCL platform found: install pocl-opencl-icd (scripts/bootstrap.sh does), or use --solver ceres";

void check(cl_int status, const char* step) {
    if (status != CL_SUCCESS)
        throw Error("", "OpenCL", std::string(step) + " failed with status " + std::to_string(status), kExitFailure);
}

struct Device {
    cl_device_id device = nullptr;
    cl_context context = nullptr;
    cl_command_queue queue = nullptr;
    std::map<std::string, cl_program> programs;
    std::string name;
};

std::mutex deviceMutex;

Device& device() {
    static Device* shared = nullptr;
    if (shared) return *shared;
    cl_uint platforms = 0;
    cl_int status = clGetPlatformIDs(0, nullptr, &platforms);
    if (status != CL_SUCCESS || platforms == 0) throw Error("", "OpenCL", kNoPlatform, kExitFailure);
    std::vector<cl_platform_id> ids(platforms);
    check(clGetPlatformIDs(platforms, ids.data(), nullptr), "clGetPlatformIDs");
    auto* created = new Device;
    for (cl_platform_id platform : ids) {
        cl_uint devices = 0;
        if (clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &created->device, &devices) == CL_SUCCESS && devices > 0)
            break;
        created->device = nullptr;
    }
    if (!created->device) {
        delete created;
        throw Error("", "OpenCL", kNoPlatform, kExitFailure);
    }
    char name[256] = {0};
    clGetDeviceInfo(created->device, CL_DEVICE_NAME, sizeof name - 1, name, nullptr);
    created->name = name;
    created->context = clCreateContext(nullptr, 1, &created->device, nullptr, nullptr, &status);
    check(status, "clCreateContext");
    created->queue = clCreateCommandQueueWithProperties(created->context, created->device, nullptr, &status);
    check(status, "clCreateCommandQueue");
    shared = created;
    return *shared;
}

cl_program build(Device& dev, const std::string& source, const std::string& options) {
    const char* text = source.c_str();
    size_t length = source.size();
    cl_int status;
    cl_program program = clCreateProgramWithSource(dev.context, 1, &text, &length, &status);
    check(status, "clCreateProgramWithSource");
    status = clBuildProgram(program, 1, &dev.device, options.c_str(), nullptr, nullptr);
    if (status != CL_SUCCESS) {
        size_t size = 0;
        clGetProgramBuildInfo(program, dev.device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
        std::string log(size, '\0');
        clGetProgramBuildInfo(program, dev.device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
        clReleaseProgram(program);
        throw Error("", "OpenCL kernel build", "failed (status " + std::to_string(status) + "); build log:\n" + log,
                    kExitFailure);
    }
    return program;
}

struct Buffer {
    cl_mem mem = nullptr;
    Buffer(cl_context context, cl_mem_flags flags, size_t bytes, const void* host) {
        cl_int status;
        mem = clCreateBuffer(context, flags | (host ? CL_MEM_COPY_HOST_PTR : 0), std::max<size_t>(bytes, 4),
                             const_cast<void*>(host), &status);
        check(status, "clCreateBuffer");
    }
    ~Buffer() { clReleaseMemObject(mem); }
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
};

} // namespace

std::string openClDeviceName() {
    std::lock_guard lock(deviceMutex);
    return device().name;
}

void buildOpenClProgram(const std::string& source, const std::string& buildOptions) {
    std::lock_guard lock(deviceMutex);
    clReleaseProgram(build(device(), source, buildOptions));
}

namespace {

// Uploads `batch`, runs kernel `name` (fitLobes or normalEquations, which share their arguments) on one work item
// per problem, and reads back the parameters into batch.params, the kernel's own costs and iterations into
// batch.cost and batch.iterations, and (normalEquations) the normal equations into *normalsOut.
void runBatch(const char* name, const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights,
              const FitBounds& bounds, const SolverOptions& options, std::vector<double>* normalsOut) {
    Device& dev = device();
    const size_t stride = (grid.count() + 7) / 8 * 8; // the kernel reads 8 directions at a time
    // The kernel keeps each lobe's values over the first CACHED x 8 directions of the grid (Values in
    // lm_kernel.cl: the whole grid up to 6 x 16^2), so the program is built per lobe count and cache size.
    const std::string buildOptions = "-D NL=" + std::to_string(batch.lobes) +
                                     " -D CACHED=" + std::to_string(std::min<size_t>(stride / 8, 192));
    cl_program& program = dev.programs[buildOptions];
    if (!program) program = build(dev, kLmKernelSource, buildOptions);
    cl_int status;
    cl_kernel kernel = clCreateKernel(program, name, &status);
    check(status, "clCreateKernel");

    const size_t problems = batch.problems, count = grid.count(), width = size_t(batch.lobes) * kLobeParams;
    const size_t padded = (problems + kLocalSize - 1) / kLocalSize * kLocalSize;
    // The grid in columns (the float directions in double: the kernel converts nothing), padded with zero-weight
    // directions; the weights in double, as objective.cpp has them.
    std::vector<double> dirX(stride, 0.0), dirY(stride, 0.0), dirZ(stride, 1.0);
    // The data term's moments (lm_kernel.cl, normalAt): solid angle times 1, x, y, z, xx, xy, xz, yy, yz, zz, for
    // every 8 directions the 10 moments' 8 values one after the other (one base address per 8 directions), zero
    // on the padding.
    std::vector<double> moments(10 * stride, 0.0);
    for (size_t i = 0; i < count; ++i) {
        dirX[i] = grid.directions[i * 3], dirY[i] = grid.directions[i * 3 + 1], dirZ[i] = grid.directions[i * 3 + 2];
        const double w[4] = {1.0, dirX[i], dirY[i], dirZ[i]}, solidAngle = grid.solidAngle[i];
        int m = 0;
        for (int a = 0; a < 4; ++a)
            for (int b = a; b < 4; ++b) moments[(i / 8 * 10 + size_t(m++)) * 8 + i % 8] = solidAngle * w[a] * w[b];
    }
    std::vector<float> kernelValues(stride * padded, 0.0f), amplitudeMax(padded, 0.0f);
    std::vector<double> energies(padded, 0.0);
    std::vector<float> priors(padded * batch.lobes * 4, 0.0f), priorWeights(padded, 0.0f), params(padded * width, 0.0f);
    for (size_t p = 0; p < problems; ++p) {
        std::copy_n(&batch.kernel[p * count], count, &kernelValues[p * stride]);
        energies[p] = dataEnergy(grid, &batch.kernel[p * count]);
        amplitudeMax[p] = batch.amplitudeMax[p];
        if (!batch.hasPrior.empty() && batch.hasPrior[p]) {
            priorWeights[p] = 1.0f;
            std::copy_n(&batch.prior[p * batch.lobes * 4], batch.lobes * 4, &priors[p * batch.lobes * 4]);
        }
    }
    std::copy_n(batch.params.begin(), problems * width, params.begin());
    for (size_t p = problems; p < padded; ++p) // padding: unit means, never fitted (energy 0)
        for (int k = 0; k < batch.lobes; ++k) params[p * width + k * kLobeParams + 1] = 1.0f;

    const cl_mem_flags in = CL_MEM_READ_ONLY;
    Buffer kernelBuffer(dev.context, in, kernelValues.size() * 4, kernelValues.data());
    Buffer dirXBuffer(dev.context, in, stride * 8, dirX.data());
    Buffer dirYBuffer(dev.context, in, stride * 8, dirY.data());
    Buffer dirZBuffer(dev.context, in, stride * 8, dirZ.data());
    Buffer momentBuffer(dev.context, in, moments.size() * 8, moments.data());
    Buffer energyBuffer(dev.context, in, padded * 8, energies.data());
    Buffer amplitudeBuffer(dev.context, in, padded * 4, amplitudeMax.data());
    Buffer priorBuffer(dev.context, in, priors.size() * 4, priors.data());
    Buffer priorWeightBuffer(dev.context, in, padded * 4, priorWeights.data());
    Buffer paramBuffer(dev.context, CL_MEM_READ_WRITE, params.size() * 4, params.data());
    Buffer costBuffer(dev.context, CL_MEM_WRITE_ONLY, padded * 8, nullptr);
    Buffer iterationBuffer(dev.context, CL_MEM_WRITE_ONLY, padded * 4, nullptr);
    const size_t normalSize = 1 + width + width * width;
    Buffer normalBuffer(dev.context, CL_MEM_WRITE_ONLY, normalsOut ? padded * normalSize * 8 : 8, nullptr);

    cl_int problemCount = cl_int(padded), gridCount = cl_int(stride);
    double beta = weights.beta, gamma = weights.gamma, delta = weights.delta, over = 1.0 + weights.overshoot;
    double logMin = std::log(bounds.lambdaMin), logMax = std::log(bounds.lambdaMax);
    cl_int maxIterations = options.maxIterations;
    int arg = 0;
    auto set = [&](size_t size, const void* value) { check(clSetKernelArg(kernel, arg++, size, value), "clSetKernelArg"); };
    set(sizeof(cl_int), &problemCount);
    set(sizeof(cl_int), &gridCount);
    for (Buffer* b : {&kernelBuffer, &dirXBuffer, &dirYBuffer, &dirZBuffer, &momentBuffer, &energyBuffer, &amplitudeBuffer,
                      &priorBuffer, &priorWeightBuffer})
        set(sizeof(cl_mem), &b->mem);
    for (const double* value : {&beta, &gamma, &delta, &over, &logMin, &logMax}) set(sizeof(double), value);
    set(sizeof(cl_int), &maxIterations);
    for (const double* value : {&options.functionTolerance, &options.parameterTolerance, &options.gradientTolerance})
        set(sizeof(double), value);
    for (Buffer* b : {&paramBuffer, &costBuffer, &iterationBuffer, &normalBuffer}) set(sizeof(cl_mem), &b->mem);
    size_t global = padded, local = kLocalSize;
    check(clEnqueueNDRangeKernel(dev.queue, kernel, 1, nullptr, &global, &local, 0, nullptr, nullptr),
          "clEnqueueNDRangeKernel");
    std::vector<double> costs(padded);
    std::vector<cl_int> iterations(padded);
    check(clEnqueueReadBuffer(dev.queue, paramBuffer.mem, CL_TRUE, 0, params.size() * 4, params.data(), 0, nullptr,
                              nullptr), "clEnqueueReadBuffer");
    check(clEnqueueReadBuffer(dev.queue, costBuffer.mem, CL_TRUE, 0, padded * 8, costs.data(), 0, nullptr, nullptr),
          "clEnqueueReadBuffer");
    check(clEnqueueReadBuffer(dev.queue, iterationBuffer.mem, CL_TRUE, 0, padded * 4, iterations.data(), 0, nullptr,
                              nullptr), "clEnqueueReadBuffer");
    if (normalsOut) {
        normalsOut->resize(padded * normalSize);
        check(clEnqueueReadBuffer(dev.queue, normalBuffer.mem, CL_TRUE, 0, normalsOut->size() * 8, normalsOut->data(), 0,
                                  nullptr, nullptr), "clEnqueueReadBuffer");
        normalsOut->resize(problems * normalSize);
    }
    clReleaseKernel(kernel);
    std::copy_n(params.begin(), problems * width, batch.params.begin());
    batch.cost.assign(problems, 0.0f);
    batch.iterations.assign(problems, 0);
    for (size_t p = 0; p < problems; ++p) { // the kernel's own objective at its (double) end point
        batch.cost[p] = float(costs[p]);
        batch.iterations[p] = iterations[p];
    }
}

} // namespace

void solveOpenCl(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const FitBounds& bounds,
                 const SolverOptions& options) {
    std::lock_guard lock(deviceMutex);
    runBatch("fitLobes", grid, batch, weights, bounds, options, nullptr);
}

std::vector<double> openClNormalEquations(const DirectionGrid& grid, const FitBatch& batch, const FitWeights& weights,
                                          const FitBounds& bounds) {
    std::lock_guard lock(deviceMutex);
    FitBatch copy = batch;
    std::vector<double> normals;
    runBatch("normalEquations", grid, copy, weights, bounds, SolverOptions{}, &normals);
    return normals;
}

} // namespace prt::glossy
