// Bounded non-linear least squares for one cone light (Ceres). The thesis tried unconstrained least squares
// (negative light weights) and NNLS (the SH absorbed the lights) and gave up; bounds on radiance and radius, a
// direction on the sphere and a background that holds the SH residual fixed make the fit well posed.
#include "envlight.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

#include <cmath>

namespace prt::envlight {

namespace {

// Every texel's residual weight * (target - radiance * cover) in one block with an analytic Jacobian: the fit runs
// on thousands of texels per light, and one autodiffed block per texel spent most of its time in Ceres's
// per-block bookkeeping (5x slower per decomposition, measured on courtyard).
class ConeResidual final : public ceres::CostFunction {
public:
    ConeResidual(const FitTexels& texels, double edge) : texels_(texels), edge_(edge) {
        set_num_residuals(int(3 * texels.solidAngles.size()));
        mutable_parameter_block_sizes()->assign({3, 3, 1}); // direction, radiance, angular radius
    }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
        const double *d = parameters[0], *radiance = parameters[1], radius = parameters[2][0];
        const double rim = 2.0 * std::sin(0.5 * radius), rimDerivative = std::cos(0.5 * radius);
        const double scale = 1.0 / (std::sqrt(2.0) * edge_), density = 1.0 / (std::sqrt(2.0 * M_PI) * edge_);
        for (size_t i = 0; i < texels_.solidAngles.size(); ++i) {
            const double* w = &texels_.directions[i * 3];
            const double offset[3] = {d[0] - w[0], d[1] - w[1], d[2] - w[2]};
            // sqrt(chord^2 + 1e-24): a finite derivative when the light's centre lies on a texel's direction.
            const double chord =
                std::sqrt(offset[0] * offset[0] + offset[1] * offset[1] + offset[2] * offset[2] + 1e-24);
            const double x = (chord - rim) * scale;
            const double cover = 0.5 * std::erfc(x);
            const double weight = std::sqrt(texels_.solidAngles[i]);
            for (int c = 0; c < 3; ++c)
                residuals[i * 3 + c] = weight * (texels_.target[i * 3 + c] - radiance[c] * cover);
            if (!jacobians) continue;
            // d cover / d chord = -exp(-x^2) / (sqrt(2 pi) edge); d chord / d d = offset / chord.
            const double slope = -std::exp(-x * x) * density;
            for (int c = 0; c < 3; ++c) {
                const double g = -weight * radiance[c];
                if (jacobians[0])
                    for (int a = 0; a < 3; ++a) jacobians[0][(i * 3 + c) * 3 + a] = g * slope * offset[a] / chord;
                if (jacobians[1])
                    for (int a = 0; a < 3; ++a) jacobians[1][(i * 3 + c) * 3 + a] = a == c ? -weight * cover : 0.0;
                if (jacobians[2]) jacobians[2][i * 3 + c] = g * -slope * rimDerivative;
            }
        }
        return true;
    }

private:
    const FitTexels& texels_;
    double edge_;
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
    LightFit fit;
    if (count == 0) {
        fit.light = initial;
        fit.termination = "no texels";
        return fit;
    }
    problem.AddResidualBlock(new ConeResidual(texels, edge), nullptr, direction.data(), radiance.data(), &radius);
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
