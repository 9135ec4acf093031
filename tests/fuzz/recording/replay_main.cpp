// Stand-alone driver for compilers without libFuzzer (gcc): replays every file of the seed
// corpus, then deterministic variants of each (every prefix up to 512 bytes, and 300
// single-byte mutations from a fixed seed) through the same LLVMFuzzerTestOneInput.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

void run(const std::string& bytes) {
  LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

std::size_t replay_variants(const std::string& seed_text, std::mt19937_64& rng) {
  std::size_t runs = 0;
  run(seed_text);
  ++runs;
  for (std::size_t n = 0; n < seed_text.size() && n < 512; ++n, ++runs) run(seed_text.substr(0, n));
  static const char kBytes[] = ",;\t \n\r\"0123456789.-+eEnaif";
  for (int i = 0; i < 300 && !seed_text.empty(); ++i, ++runs) {
    std::string m = seed_text;
    const std::size_t at = rng() % m.size();
    switch (rng() % 3) {
      case 0: m[at] = kBytes[rng() % (sizeof(kBytes) - 1)]; break;
      case 1: m.erase(at, 1); break;
      default: m.insert(at, 1, kBytes[rng() % (sizeof(kBytes) - 1)]); break;
    }
    run(m);
  }
  return runs;
}

}  // namespace

int main(int argc, char** argv) {
  std::mt19937_64 rng(20261121);
  std::size_t files = 0, runs = 0;
  for (int a = 1; a < argc; ++a) {
    std::vector<std::filesystem::path> paths;
    if (std::filesystem::is_directory(argv[a])) {
      for (const auto& e : std::filesystem::directory_iterator(argv[a])) paths.push_back(e.path());
    } else {
      paths.emplace_back(argv[a]);
    }
    std::sort(paths.begin(), paths.end());
    for (const auto& p : paths) {
      std::ifstream in(p, std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      runs += replay_variants(text, rng);
      ++files;
    }
  }
  std::printf("replayed %zu corpus files, %zu inputs (seed 20261121)\n", files, runs);
  return files > 0 ? 0 : 1;
}
