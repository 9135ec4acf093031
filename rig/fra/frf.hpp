// Models as response callbacks for the FRA layer. The FRF point type itself is
// rig::model::FrfPoint (rig/model/frf.hpp, the leaf library).
//
// A model enters the FRA layer as a response callback H(j 2 pi f) so that any model type
// (rig::model::TransferFunction, a plant linearisation, an analytic test system) can be used
// without this layer depending on it; `as_response_fn` adapts anything with
// `std::complex<double> response(double freq_hz) const`.
#pragma once

#include <complex>
#include <concepts>
#include <functional>
#include <vector>

#include "rig/model/frf.hpp"

namespace rig::fra {

// H(j 2 pi f) of a model, in output units per input unit (kW per % of rated power).
using ResponseFn = std::function<std::complex<double>(double freq_hz)>;

template <class Model>
concept HasResponse = requires(const Model& m, double f) {
  { m.response(f) } -> std::convertible_to<std::complex<double>>;
};

// Wraps a model object; the model must outlive the returned callback.
template <HasResponse Model>
ResponseFn as_response_fn(const Model& model) {
  return [&model](double freq_hz) { return std::complex<double>(model.response(freq_hz)); };
}

}  // namespace rig::fra
