#include "dasp/spectral.h"

#include <Spectra/SymEigsShiftSolver.h>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

namespace dasp {
namespace {

void checkGraph(const WeightedGraph& graph, const char* what) {
  if (graph.node_count < 0) {
    throw std::invalid_argument(std::string(what) + ": negative node_count");
  }
  for (const GraphEdge& e : graph.edges) {
    if (e.a < 0 || e.b < 0 || e.a >= graph.node_count || e.b >= graph.node_count || e.a == e.b) {
      throw std::invalid_argument(std::string(what) + ": edge (" + std::to_string(e.a) + ", " +
                                  std::to_string(e.b) + ") out of range or a loop");
    }
    if (!(e.weight >= 0.0f) || !std::isfinite(e.weight)) {
      throw std::invalid_argument(std::string(what) + ": edge weights must be finite and >= 0");
    }
  }
}

Eigen::VectorXd degrees(const WeightedGraph& graph) {
  Eigen::VectorXd degree = Eigen::VectorXd::Zero(graph.node_count);
  for (const GraphEdge& e : graph.edges) {
    degree[e.a] += e.weight;
    degree[e.b] += e.weight;
  }
  return degree;
}

Eigen::VectorXd inverseSqrtDegrees(const WeightedGraph& graph, const char* what) {
  Eigen::VectorXd degree = degrees(graph);
  for (int i = 0; i < graph.node_count; ++i) {
    if (!(degree[i] > 0.0)) {
      throw std::invalid_argument(std::string(what) +
                                  ": every node needs a positive degree (connected graph)");
    }
    degree[i] = 1.0 / std::sqrt(degree[i]);
  }
  return degree;
}

// Eigenvectors y of the normalised Laplacian have unit norm; x = D^-1/2 y then has x^T D x = 1.
// The sign of each vector is fixed (largest-magnitude entry positive) so results are repeatable.
Eigenpairs toGeneralised(const Eigen::VectorXd& values, const Eigen::MatrixXd& vectors,
                         const Eigen::VectorXd& inv_sqrt_degree) {
  Eigenpairs pairs;
  pairs.values = values;
  pairs.vectors = inv_sqrt_degree.asDiagonal() * vectors;
  for (Eigen::Index t = 0; t < pairs.vectors.cols(); ++t) {
    Eigen::Index index = 0;
    pairs.vectors.col(t).cwiseAbs().maxCoeff(&index);
    if (pairs.vectors(index, t) < 0.0) pairs.vectors.col(t) *= -1.0;
  }
  return pairs;
}

// (L_sym - sigma I)^-1 for Spectra's shift-and-invert mode; L_sym is positive semi-definite, so a
// negative shift makes the matrix positive definite and a sparse LDL^T factorisation suffices.
class NormalizedLaplacianShiftSolve {
 public:
  using Scalar = double;
  explicit NormalizedLaplacianShiftSolve(const Eigen::SparseMatrix<double>& laplacian)
      : laplacian_(laplacian) {}
  Eigen::Index rows() const { return laplacian_.rows(); }
  Eigen::Index cols() const { return laplacian_.cols(); }
  void set_shift(const double& sigma) {
    Eigen::SparseMatrix<double> identity(laplacian_.rows(), laplacian_.cols());
    identity.setIdentity();
    solver_.compute(laplacian_ - sigma * identity);
    if (solver_.info() != Eigen::Success) {
      throw std::runtime_error("smallestEigenpairs: factorisation of the shifted Laplacian failed");
    }
  }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, laplacian_.rows());
    Eigen::Map<Eigen::VectorXd> y(y_out, laplacian_.rows());
    y = solver_.solve(x);
  }

 private:
  const Eigen::SparseMatrix<double>& laplacian_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
};

int find(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

Eigenpairs smallestEigenpairsDense(const WeightedGraph& graph, int count) {
  const char* what = "smallestEigenpairsDense";
  checkGraph(graph, what);
  if (count < 1) throw std::invalid_argument("smallestEigenpairsDense: count must be >= 1");
  const int n = graph.node_count;
  const Eigen::VectorXd inv_sqrt_degree = inverseSqrtDegrees(graph, what);
  Eigen::MatrixXd laplacian = Eigen::MatrixXd::Identity(n, n);
  for (const GraphEdge& e : graph.edges) {
    const double value = -e.weight * inv_sqrt_degree[e.a] * inv_sqrt_degree[e.b];
    laplacian(e.a, e.b) += value;
    laplacian(e.b, e.a) += value;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(laplacian);
  const int m = std::min(count, n);
  return toGeneralised(solver.eigenvalues().head(m), solver.eigenvectors().leftCols(m),
                       inv_sqrt_degree);
}

Eigenpairs smallestEigenpairs(const WeightedGraph& graph, int count, const SpectralConfig& config) {
  const char* what = "smallestEigenpairs";
  checkGraph(graph, what);
  if (count < 1) throw std::invalid_argument("smallestEigenpairs: count must be >= 1");
  const int n = graph.node_count;
  // Lanczos needs nev < ncv <= n; small or nearly complete requests go to the dense solver.
  if (n <= config.dense_max_nodes || count + 1 >= n / 2) {
    return smallestEigenpairsDense(graph, count);
  }
  const Eigen::VectorXd inv_sqrt_degree = inverseSqrtDegrees(graph, what);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(graph.edges.size() * 2 + static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, 1.0);
  for (const GraphEdge& e : graph.edges) {
    const double value = -e.weight * inv_sqrt_degree[e.a] * inv_sqrt_degree[e.b];
    triplets.emplace_back(e.a, e.b, value);
    triplets.emplace_back(e.b, e.a, value);
  }
  Eigen::SparseMatrix<double> laplacian(n, n);
  laplacian.setFromTriplets(triplets.begin(), triplets.end());

  NormalizedLaplacianShiftSolve op(laplacian);
  const int ncv = std::min(n, std::max(2 * count + 1, count + 20));
  constexpr double kShift = -1e-3;  // below the smallest eigenvalue 0 of L_sym
  Spectra::SymEigsShiftSolver<NormalizedLaplacianShiftSolve> solver(op, count, ncv, kShift);
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  Eigen::VectorXd start(n);
  for (int i = 0; i < n; ++i) start[i] = uniform(rng);
  solver.init(start.data());
  solver.compute(Spectra::SortRule::LargestMagn, config.max_iterations, config.tolerance,
                 Spectra::SortRule::SmallestAlge);
  if (solver.info() != Spectra::CompInfo::Successful) {
    // Rare (clustered spectra): the dense solver is slower but always answers.
    return smallestEigenpairsDense(graph, count);
  }
  return toGeneralised(solver.eigenvalues(), solver.eigenvectors(), inv_sqrt_degree);
}

std::vector<float> globalizeEdgeWeights(const WeightedGraph& graph, const SpectralConfig& config) {
  checkGraph(graph, "globalizeEdgeWeights");
  if (config.eigenvector_count < 1) {
    throw std::invalid_argument("globalizeEdgeWeights: eigenvector_count must be >= 1");
  }
  const int n = graph.node_count;
  std::vector<float> global(graph.edges.size(), 0.0f);
  if (graph.edges.empty()) return global;

  // Connected components over the edges that carry a connection (weight > 0).
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  for (const GraphEdge& e : graph.edges) {
    if (e.weight > 0.0f) parent[find(parent, e.a)] = find(parent, e.b);
  }
  std::vector<int> component(static_cast<std::size_t>(n), -1);
  std::vector<int> local_index(static_cast<std::size_t>(n), -1);
  std::vector<WeightedGraph> parts;
  for (int i = 0; i < n; ++i) {
    const int root = find(parent, i);
    if (component[root] < 0) {
      component[root] = static_cast<int>(parts.size());
      parts.emplace_back();
    }
    component[i] = component[root];
    local_index[i] = parts[component[i]].node_count++;
  }
  std::vector<std::vector<std::size_t>> part_edges(parts.size());
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const GraphEdge& e = graph.edges[k];
    if (component[e.a] != component[e.b] || e.weight <= 0.0f) continue;
    WeightedGraph& part = parts[component[e.a]];
    part.edges.push_back({local_index[e.a], local_index[e.b], e.weight});
    part_edges[component[e.a]].push_back(k);
  }

  float largest = 0.0f;
  for (std::size_t c = 0; c < parts.size(); ++c) {
    const WeightedGraph& part = parts[c];
    if (part.node_count < 2 || part.edges.empty()) continue;
    // The smallest eigenvalue of a connected component is the trivial 0 (constant x).
    const int nontrivial = std::min(config.eigenvector_count, part.node_count - 1);
    const Eigenpairs pairs = smallestEigenpairs(part, nontrivial + 1, config);
    for (std::size_t j = 0; j < part.edges.size(); ++j) {
      const GraphEdge& e = part.edges[j];
      double sum = 0.0;
      for (Eigen::Index t = 1; t < pairs.values.size(); ++t) {
        const double lambda = std::max(pairs.values[t], config.min_eigenvalue);
        sum += std::abs(pairs.vectors(e.a, t) - pairs.vectors(e.b, t)) / std::sqrt(lambda);
      }
      global[part_edges[c][j]] = static_cast<float>(sum);
      largest = std::max(largest, static_cast<float>(sum));
    }
  }
  // Edges without connection (weight 0, or between components) get the largest weight of the
  // graph: the strongest boundary (they merge only above every other edge).
  const float unconnected = largest > 0.0f ? largest : 1.0f;
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const GraphEdge& e = graph.edges[k];
    if (e.weight <= 0.0f || component[e.a] != component[e.b]) global[k] = unconnected;
  }
  if (config.normalization == GlobalWeightNormalization::kMax) {
    for (float& w : global) w /= unconnected;
  }
  return global;
}

}  // namespace dasp
