// Whole-file writes that a concurrent reader (or a crash) never sees half done: the text
// goes to `path.tmp`, is flushed to disk, and is renamed over `path` (rename is atomic).
#pragma once

#include <filesystem>
#include <string_view>

namespace rig::model {

// Throws InputError (naming the file) when the folder is not writable.
void write_file_atomic(const std::filesystem::path& path, std::string_view text);

// Reads a whole file; InputError when it cannot be opened.
std::string read_file_text(const std::filesystem::path& path);

}  // namespace rig::model
