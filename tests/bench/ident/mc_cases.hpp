#pragma once

#include <cstdint>
#include <cstdio>

namespace rig::ident::bench {

struct McConfig {
  int runs = 200;
  std::uint64_t seed = 1;
  double minutes = 10.0;
  int lags = 512;
  std::FILE* csv = nullptr;  // per-run values (case,run,seed,method,fn_hz,zeta,gain,delay_s)
};

void noise_free_table();
void thesis_513_table();
void zero_shift_table();
void stornoway_mc(const McConfig& cfg);
void rao_garnier_mc(const McConfig& cfg);
void order_tables(const McConfig& cfg);

}  // namespace rig::ident::bench
