// Bounded non-linear least squares for one cone light (Ceres). The thesis tried unconstrained least squares
// (negative light weights) and NNLS (the SH absorbed the lights) and gave up; bounds on radiance and radius, a
// direction on the sphere and a background that holds the SH residual fixed make the fit well posed.
#include "envlight.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

#include <cmath>

namespace prt::envlight {

namespace {

struct TexelResidual {
    double w[3];
    double target[3];
    double weight; // sqrt(solid angle)
    double edge;

    template <typename T>
    bool operator()(const T* direction, const T* radiance, const T* radius, T* residual) const {
        T chord2 = (direction[0] - w[0]) * (direction[0] - w[0]) + (direction[1] - w[1]) * (direction[1] - w[1]) +
                   (direction[2] - w[2]) * (direction[2] - w[2]);
        T chord = sqrt(chord2 + T(1e-24)); // finite derivative at the centre
        T rim = T(2.0) * sin(radius[0] * T(0.5));
        T cover = T(0.5) * erfc((chord - rim) / T(std::sqrt(2.0) * edge));
        for (int c = 0; c < 3; ++c) residual[c] = T(weight) * (T(target[c]) - radiance[c] * cover);
        return true;
    }
};

double coverOf(const double* d, const double* w, double radius, double edge) {
    double chord = std::sqrt((d[0] - w[0]) * (d[0] - w[0]) + (d[1] - w[1]) * (d[1] - w[1]) + (d[2] - w[2]) * (d[2] - w[2]));
    return 0.5 * std::erfc((chord - 2.0 * std::sin(0.5 * radius)) / (std::sqrt(2.0) * edge));
}

} // namespace

LightFit fitLight(const FitTexels& texels, const ConeLight& initial, double minRadius, double maxRadius, double edge) {
    std::array<double, 3> direction = initial.direction, radiance = initial.radiance;
    double radius = std::clamp(initial.angularRadius, minRadius, maxRadius);
    ceres::Problem problem;
    const size_t count = texels.solidAngles.size();
    for (size_t i = 0; i < count; ++i) {
        auto* functor = new TexelResidual;
        for (int c = 0; c < 3; ++c) {
            functor->w[c] = texels.directions[i * 3 + c];
            functor->target[c] = texels.target[i * 3 + c];
        }
        functor->weight = std::sqrt(texels.solidAngles[i]);
        functor->edge = edge;
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TexelResidual, 3, 3, 3, 1>(functor), nullptr,
                                 direction.data(), radiance.data(), &radius);
    }
    LightFit fit;
    if (count == 0) {
        fit.light = initial;
        fit.termination = "no texels";
        return fit;
    }
    problem.SetManifold(direction.data(), new ceres::SphereManifold<3>);
    for (int c = 0; c < 3; ++c) problem.SetParameterLowerBound(radiance.data(), c, 0.0);
    problem.SetParameterLowerBound(&radius, 0, minRadius);
    problem.SetParameterUpperBound(&radius, 0, maxRadius);

    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.num_threads = 1; // deterministic
    options.max_num_iterations = 50;
    options.function_tolerance = 1e-10;
    options.parameter_tolerance = 1e-10;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);

    double length = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
    for (double& x : direction) x /= length;
    // Keep the energy the soft-edged model holds: sum radiance * cover * solid angle = radiance' * cone solid angle.
    double covered = 0.0;
    for (size_t i = 0; i < count; ++i)
        covered += coverOf(direction.data(), &texels.directions[i * 3], radius, edge) * texels.solidAngles[i];
    double scale = covered / coneSolidAngle(radius);
    fit.light.direction = direction;
    for (int c = 0; c < 3; ++c) fit.light.radiance[c] = std::max(0.0, radiance[c] * scale);
    fit.light.angularRadius = radius;
    fit.initialCost = summary.initial_cost;
    fit.finalCost = summary.final_cost;
    fit.iterations = int(summary.iterations.size());
    fit.termination = ceres::TerminationTypeToString(summary.termination_type);
    return fit;
}

} // namespace prt::envlight
