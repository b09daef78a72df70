#include "physgrad/nn/network.hpp"

#include <cblas.h>
#include <cxxabi.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <typeinfo>

#include "physgrad/error.hpp"

namespace physgrad {

std::string Network::name() const {
  const char* mangled = typeid(*this).name();
  int status = 0;
  const std::unique_ptr<char, decltype(&std::free)> readable(
      abi::__cxa_demangle(mangled, nullptr, nullptr, &status), &std::free);
  return status == 0 && readable ? readable.get() : mangled;
}

nlohmann::json Network::describe() const {
  return {{"kind", name()}, {"parameters", num_parameters()}};
}

void Network::set_parameters(const Vector& theta) {
  if (theta.size() != num_parameters()) {
    throw Error("set_parameters: got " + std::to_string(theta.size()) +
                " parameters, the network has " + std::to_string(num_parameters()));
  }
  parameters() = theta;  // same size: Eigen copies into the existing storage
}

Matrix Network::forward(const Matrix& x) const {
  const std::unique_ptr<NetworkCache> cache = new_cache();
  if (!cache) throw Error("network '" + name() + "': new_cache returned no cache");
  return forward(x, *cache);
}

Matrix Network::per_sample_gradients(const NetworkCache& cache, const Matrix& gy) const {
  Matrix out(gy.cols(), num_parameters());
  per_sample_gradients(cache, gy, out);
  return out;
}

Matrix Network::per_sample_gram(const NetworkCache& cache,
                                const std::vector<Matrix>& cotangents) const {
  // The rows of all K·B cotangents, then J Jᵀ of the lower triangle by dsyrk, mirrored.
  const Index batch = cotangents.empty() ? 0 : cotangents.front().cols();
  Matrix rows(batch * static_cast<Index>(cotangents.size()), num_parameters());
  for (std::size_t k = 0; k < cotangents.size(); ++k) {
    if (cotangents[k].cols() != batch) {
      throw Error("per_sample_gram: cotangent block " + std::to_string(k) + " has " +
                  std::to_string(cotangents[k].cols()) + " columns, block 0 has " +
                  std::to_string(batch));
    }
    per_sample_gradients(cache, cotangents[k],
                         rows.middleRows(static_cast<Index>(k) * batch, batch));
  }
  const auto n = static_cast<blasint>(rows.rows());
  Matrix gram = Matrix::Zero(rows.rows(), rows.rows());
  if (rows.size() != 0) {
    cblas_dsyrk(CblasColMajor, CblasLower, CblasNoTrans, n, static_cast<blasint>(rows.cols()),
                1.0, rows.data(), n, 0.0, gram.data(), n);
  }
  gram.triangularView<Eigen::StrictlyUpper>() = gram.transpose();
  return gram;
}

Matrix Network::per_sample_gram_columns(const NetworkCache& cache,
                                        const std::vector<Matrix>& cotangents,
                                        const std::vector<Index>& selected) const {
  const Matrix gram = per_sample_gram(cache, cotangents);
  Matrix out(gram.rows(), static_cast<Index>(selected.size()));
  for (std::size_t s = 0; s < selected.size(); ++s) {
    if (selected[s] < 0 || selected[s] >= gram.cols()) {
      throw Error("per_sample_gram_columns: column " + std::to_string(selected[s]) +
                  " outside [0, " + std::to_string(gram.cols()) + ")");
    }
    out.col(static_cast<Index>(s)) = gram.col(selected[s]);
  }
  return out;
}

Matrix Network::jvp(const NetworkCache& cache, Index batch, const Vector& v) const {
  const Index parameters = num_parameters();
  if (v.size() != parameters) {
    throw Error("network '" + name() + "': jvp along " + std::to_string(v.size()) +
                " entries, num_parameters() says " + std::to_string(parameters));
  }
  // Row o of the result is (∂f_o(x_b)/∂θ) · v: the gradient rows of the unit cotangent e_o.
  const Index outputs = output_dim();
  Matrix out(outputs, batch);
  Matrix unit(outputs, batch);
  Matrix rows(batch, parameters);
  for (Index o = 0; o < outputs; ++o) {
    unit.setZero();
    unit.row(o).setOnes();
    per_sample_gradients(cache, unit, rows);
    out.row(o) = (rows * v).transpose();
  }
  return out;
}

std::vector<DenseLayerFactors> Network::dense_layer_factors(
    const NetworkCache& /*cache*/, const std::vector<Matrix>& /*cotangents*/) const {
  throw Error("network '" + name() +
              "' does not describe its dense layers (dense_layer_factors), which the "
              "Kronecker-factored rules need");
}

}  // namespace physgrad
