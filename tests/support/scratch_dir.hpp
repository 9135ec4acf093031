// A test's scratch folder under the system's temp folder, named after the process and the
// test, made empty. The folders a test program made (and files named after them beside
// them) are removed when it exits with every test it ran passed; a failing run's stay.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

namespace rig::testing {

class ScratchDirs {
 public:
  static ScratchDirs& instance() {
    static ScratchDirs dirs;
    return dirs;
  }

  std::filesystem::path make(const std::string& prefix, const std::string& name) {
    const auto dir =
        std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()) + "-" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::lock_guard lock(mutex_);
    dirs_.push_back(dir);
    return dir;
  }

  ~ScratchDirs() {
    // The gtest singleton outlives static objects (it is never deleted).
    if (!::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    for (const auto& dir : dirs_) {
      std::filesystem::remove_all(dir, ignored);
      // and the files a test named after it beside it (dir.log, dir.model.json)
      const std::string stem = dir.filename().string() + ".";
      for (const auto& e : std::filesystem::directory_iterator(dir.parent_path(), ignored))
        if (e.path().filename().string().starts_with(stem)) std::filesystem::remove_all(e, ignored);
    }
  }

 private:
  ScratchDirs() = default;
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

// prefix + pid + "-" + name, e.g. /tmp/rig-commission-1234-dip.
inline std::filesystem::path scratch_dir(const std::string& prefix, const std::string& name) {
  return ScratchDirs::instance().make(prefix, name);
}

}  // namespace rig::testing
