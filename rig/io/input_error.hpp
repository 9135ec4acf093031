// The input-file error and the checked opening of input files live in the leaf library
// (rig/model/input_error.hpp) because the model and FRF readers there need them; rig::io
// uses the same type under its own name (docs/decisions.md).
#pragma once

#include "rig/model/input_error.hpp"

namespace rig::io {

using model::InputError;
using model::InputFile;
using model::read_small_input_file;

}  // namespace rig::io
