// Monte Carlo and thesis-reproduction tables for the identification methods.
//   bench_ident_mc --case stornoway|rao|thesis513|zeroshift|noisefree|orders|all --runs N --seed S
//                  [--minutes M] [--lags L] [--csv FILE]
// Every table prints the seed; run r uses seed + r.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "tests/bench/ident/mc_cases.hpp"

int main(int argc, char** argv) {
  rig::ident::bench::McConfig cfg;
  std::string which = "all";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const char* v = argv[i + 1];
    if (k == "--case") which = v;
    else if (k == "--runs") cfg.runs = std::atoi(v);
    else if (k == "--seed") cfg.seed = std::strtoull(v, nullptr, 10);
    else if (k == "--minutes") cfg.minutes = std::atof(v);
    else if (k == "--lags") cfg.lags = std::atoi(v);
    else if (k == "--csv") cfg.csv = std::fopen(v, "w");
    else {
      std::fprintf(stderr, "bench_ident_mc: unknown option %s (expected --case, --runs, "
                           "--seed, --minutes, --lags, --csv)\n", k.c_str());
      return 2;
    }
  }
  if (which == "noisefree" || which == "all") rig::ident::bench::noise_free_table();
  if (which == "zeroshift" || which == "all") rig::ident::bench::zero_shift_table();
  if (which == "thesis513" || which == "all") rig::ident::bench::thesis_513_table();
  if (which == "stornoway" || which == "all") rig::ident::bench::stornoway_mc(cfg);
  if (which == "rao" || which == "all") rig::ident::bench::rao_garnier_mc(cfg);
  if (which == "orders" || which == "all") rig::ident::bench::order_tables(cfg);
  if (cfg.csv) std::fclose(cfg.csv);
  return 0;
}
