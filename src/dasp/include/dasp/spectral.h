// s-DASP globalisation (thesis §4.3.2): spectral graph theory turns the local superpixel
// similarities into a global boundary detector on the superpixel graph, the ultrametric contour
// graph (UCG).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "dasp/superpixel_graph.h"

namespace dasp {

/// How the globalised weights of one graph are scaled.
enum class GlobalWeightNormalization {
  kNone,  ///< eq. 4.22 as printed (eigenvectors with x^T D x = 1).
  kMax,   ///< divided by the largest weight of the graph, so that they lie in [0, 1].
};

/// Parameters of the spectral globalisation.
struct SpectralConfig {
  /// k: number of non-trivial eigenpairs (the smallest eigenvalues above the trivial 0 of each
  /// connected component) summed in eq. 4.22. Clamped to (component size - 1). >= 1.
  int eigenvector_count = 16;
  GlobalWeightNormalization normalization = GlobalWeightNormalization::kMax;
  /// Components with at most this many nodes are solved with a dense eigensolver; larger ones
  /// with the sparse shift-and-invert Lanczos solver of Spectra.
  int dense_max_nodes = 64;
  /// Eigenvalues are clamped to at least this before 1/sqrt(lambda), so that (numerically)
  /// disconnected pieces give a large finite weight rather than infinity.
  double min_eigenvalue = 1e-9;
  double tolerance = 1e-8;    ///< Spectra convergence tolerance.
  int max_iterations = 1000;  ///< Spectra restart limit.
  std::uint64_t seed = 0;     ///< Seed of the start vector of the sparse solver.
};

/// The k smallest eigenpairs of the generalised problem L x = lambda D x of one graph (eq. 4.11),
/// through the normalised Laplacian D^-1/2 L D^-1/2 y = lambda y, x = D^-1/2 y (eq. 4.12).
struct Eigenpairs {
  Eigen::VectorXd values;   ///< ascending
  Eigen::MatrixXd vectors;  ///< column t = x_t, normalised so that x^T D x = 1
};

/// The `count` smallest eigenpairs of a connected graph with positive degrees (Spectra, sparse;
/// or dense when node_count <= config.dense_max_nodes). count is clamped to node_count.
/// Throws std::invalid_argument when a node has zero degree or count < 1.
Eigenpairs smallestEigenpairs(const WeightedGraph& graph, int count,
                              const SpectralConfig& config = {});

/// The same with a dense Eigen solver on the full matrix, for tests and tiny graphs.
Eigenpairs smallestEigenpairsDense(const WeightedGraph& graph, int count);

/// s-DASP globalisation (4.3.2, eq. 4.22): returns one globalised boundary weight per edge of
/// `graph`, same order (larger = stronger boundary), sum over the k non-trivial eigenpairs of
/// 1/sqrt(lambda_t) |x_ti - x_tj|, computed per connected component. Handles disconnected
/// graphs, tiny graphs and k >= n. Edge weights must be >= 0; edges of weight 0 carry no
/// connection and, like edges between components, get the largest weight of the graph (the
/// strongest boundary). Throws std::invalid_argument for edges out of range, loops or negative
/// weights.
std::vector<float> globalizeEdgeWeights(const WeightedGraph& graph,
                                        const SpectralConfig& config = {});

}  // namespace dasp
