// The output folder of a command (DESIGN.md section 4): a run never leaves an earlier run's
// files beside its own. prepare_out_dir() is called before anything is written to a governor
// or a plant is started; it refuses (OutDirError, exit code 2):
//   * a path that exists and is not a folder;
//   * a folder that holds anything, unless force (then its contents are removed first);
//   * a folder that cannot be created or written (a probe file is created and removed).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace rig::io {

struct OutDirError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void prepare_out_dir(const std::filesystem::path& dir, bool force);

}  // namespace rig::io
