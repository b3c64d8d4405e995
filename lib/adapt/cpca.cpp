// Clustered PCA (Sloan, Hall, Hart and Snyder 2003): k-means clusters of transfer vectors, each approximated by its
// mean plus a few principal directions, solved with Eigen.
#include "adapt.h"

#include "core.h"

#include <Eigen/Dense>

#include <limits>

namespace prt::adapt {

std::vector<uint32_t> kMeans(const float* data, size_t rows, size_t dim, int clusterCount, int iterations) {
    if (clusterCount < 1 || size_t(clusterCount) > rows)
        throw Error("", "kMeans", std::to_string(clusterCount) + " clusters for " + std::to_string(rows) + " rows",
                    kExitUsage);
    using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> points(data, rows, dim);
    Matrix centres(clusterCount, dim);
    for (int k = 0; k < clusterCount; ++k) centres.row(k) = points.row(size_t(k) * rows / clusterCount).cast<double>();
    std::vector<uint32_t> cluster(rows, 0);
    for (int iteration = 0; iteration < iterations; ++iteration) {
        bool changed = false;
        for (size_t r = 0; r < rows; ++r) {
            Eigen::RowVectorXd point = points.row(r).cast<double>();
            double best = std::numeric_limits<double>::infinity();
            uint32_t bestCluster = 0;
            for (int k = 0; k < clusterCount; ++k) {
                double distance = (centres.row(k) - point).squaredNorm();
                if (distance < best) best = distance, bestCluster = uint32_t(k);
            }
            changed |= cluster[r] != bestCluster || iteration == 0;
            cluster[r] = bestCluster;
        }
        if (!changed) break;
        Matrix sums = Matrix::Zero(clusterCount, dim);
        std::vector<size_t> counts(clusterCount, 0);
        for (size_t r = 0; r < rows; ++r) sums.row(cluster[r]) += points.row(r).cast<double>(), ++counts[cluster[r]];
        for (int k = 0; k < clusterCount; ++k)
            if (counts[k]) centres.row(k) = sums.row(k) / double(counts[k]); // an empty cluster keeps its centre
    }
    return cluster;
}

Cpca clusteredPca(const float* data, size_t rows, size_t dim, int clusterCount, int components, int iterations) {
    if (components < 0 || size_t(components) > dim)
        throw Error("", "--components", std::to_string(components) + " components for vectors of " +
                                            std::to_string(dim) + " values", kExitUsage);
    Cpca cpca;
    cpca.clusterCount = clusterCount;
    cpca.components = components;
    cpca.dim = dim;
    cpca.cluster = kMeans(data, rows, dim, clusterCount, iterations);
    cpca.basis.assign(size_t(clusterCount) * (components + 1) * dim, 0.0f);
    cpca.weights.assign(rows * components, 0.0f);
    Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> points(data, rows, dim);
    for (int k = 0; k < clusterCount; ++k) {
        std::vector<size_t> members;
        for (size_t r = 0; r < rows; ++r)
            if (cpca.cluster[r] == uint32_t(k)) members.push_back(r);
        if (members.empty()) continue;
        Eigen::MatrixXd centred(members.size(), dim);
        for (size_t i = 0; i < members.size(); ++i) centred.row(i) = points.row(members[i]).cast<double>();
        Eigen::RowVectorXd mean = centred.colwise().mean();
        centred.rowwise() -= mean;
        // Eigenvalues come ascending; the principal directions are the last columns.
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(centred.transpose() * centred);
        Eigen::MatrixXd directions = solver.eigenvectors().rightCols(components).rowwise().reverse();
        float* block = cpca.basis.data() + size_t(k) * (components + 1) * dim;
        for (size_t d = 0; d < dim; ++d) block[d] = float(mean[d]);
        for (int i = 0; i < components; ++i)
            for (size_t d = 0; d < dim; ++d) block[(i + 1) * dim + d] = float(directions(d, i));
        Eigen::MatrixXd weights = centred * directions;
        for (size_t i = 0; i < members.size(); ++i)
            for (int c = 0; c < components; ++c) cpca.weights[members[i] * components + c] = float(weights(i, c));
    }
    return cpca;
}

std::vector<float> reconstruct(const Cpca& cpca) {
    const size_t rows = cpca.cluster.size(), dim = cpca.dim;
    std::vector<float> out(rows * dim);
    for (size_t r = 0; r < rows; ++r) {
        const float* block = cpca.basis.data() + size_t(cpca.cluster[r]) * (cpca.components + 1) * dim;
        for (size_t d = 0; d < dim; ++d) {
            float value = block[d];
            for (int i = 0; i < cpca.components; ++i)
                value += cpca.weights[r * cpca.components + i] * block[(i + 1) * dim + d];
            out[r * dim + d] = value;
        }
    }
    return out;
}

} // namespace prt::adapt
