// Atomic whole-file writes live in the leaf library (rig/model/atomic_file.hpp) because the
// model and FRF writers there need them; rig::io uses them under its own names.
#pragma once

#include "rig/model/atomic_file.hpp"

namespace rig::io {

using model::read_file_text;
using model::write_file_atomic;

}  // namespace rig::io
