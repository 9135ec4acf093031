// Plant configuration: TOML, presets, timed changes and the one-line errors for bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "plantsim/plant/config.hpp"

namespace plantsim {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "error must be one line: " << what;
    return what;
  }
  ADD_FAILURE() << "expected ConfigError";
  return {};
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(PlantConfig, EveryParameterHasUnitAndDefaultInRange) {
  for (const auto& s : param_specs()) {
    EXPECT_FALSE(s.unit.empty()) << s.name;
    EXPECT_LE(s.min_value, s.default_value) << s.name;
    EXPECT_GE(s.max_value, s.default_value) << s.name;
    EXPECT_NE(s.name.find('.'), std::string_view::npos) << s.name;
  }
}

TEST(PlantConfig, TomlOverridesOnTopOfPreset) {
  const Params p = parse_toml(
      "preset = \"stornoway\"\n[gov]\nr_pu = 0.04\n[alt]\nflux_decay = true\n", "x.toml");
  Params expected = preset("stornoway");
  expected.set(P::kGovR, 0.04, "test");
  expected.set(P::kAltFluxDecay, 1.0, "test");
  EXPECT_TRUE(p == expected);
}

TEST(PlantConfig, UnknownParameterNamesFileLineAndKey) {
  const auto msg = error_of([] { parse_toml("[gov]\nr_pu = 0.05\nrr_pu = 0.1\n", "plant.toml"); });
  EXPECT_TRUE(contains(msg, "plant.toml:3")) << msg;
  EXPECT_TRUE(contains(msg, "gov.rr_pu")) << msg;
}

TEST(PlantConfig, OutOfRangeNamesKeyAndRange) {
  const auto msg = error_of([] { parse_toml("[alt]\nh_s = -1\n", "plant.toml"); });
  EXPECT_TRUE(contains(msg, "plant.toml:2")) << msg;
  EXPECT_TRUE(contains(msg, "alt.h_s")) << msg;
  EXPECT_TRUE(contains(msg, "expected 0.05 .. 30")) << msg;
}

TEST(PlantConfig, MalformedTomlGivesLineNumber) {
  const auto msg = error_of([] { parse_toml("[gov]\nr_pu = 0.05\nt1_s = = 3\n", "bad.toml"); });
  EXPECT_TRUE(contains(msg, "bad.toml:3")) << msg;
  EXPECT_TRUE(contains(msg, "malformed TOML")) << msg;
}

TEST(PlantConfig, WrongTypeAndStrayTopLevelKey) {
  EXPECT_TRUE(contains(error_of([] { parse_toml("[gov]\nr_pu = \"x\"\n", "p.toml"); }),
                       "must be a number"));
  EXPECT_TRUE(contains(error_of([] { parse_toml("r_pu = 1\n", "p.toml"); }), "must be a table"));
}

TEST(PlantConfig, UnknownPresetListsTheKnownOnes) {
  const auto msg = error_of([] { preset("stornaway"); });
  EXPECT_TRUE(contains(msg, "stornaway")) << msg;
  EXPECT_TRUE(contains(msg, "stornoway")) << msg;
}

TEST(PlantConfig, MissingFileIsAConfigError) {
  const auto msg = error_of([] { load_toml("/nonexistent/plant.toml"); });
  EXPECT_TRUE(contains(msg, "/nonexistent/plant.toml")) << msg;
}

TEST(PlantConfig, FaultStringsParse) {
  const TimedChange c = parse_change("injector_3=0@t=20.5");
  EXPECT_EQ(c.param, P::kInjector3);
  EXPECT_EQ(c.value, 0.0);
  EXPECT_EQ(c.time_s, 20.5);
  EXPECT_EQ(parse_change("engine.boost_lag_s=6@t=30").param, P::kEngBoostLag);
}

TEST(PlantConfig, MalformedFaultStringsAreRejected) {
  EXPECT_TRUE(contains(error_of([] { parse_change("injector_3=0"); }), "NAME=VALUE@t=SECONDS"));
  EXPECT_TRUE(contains(error_of([] { parse_change("injector_33=0@t=1"); }), "unknown parameter"));
  EXPECT_TRUE(contains(error_of([] { parse_change("injector_3=x@t=1"); }), "VALUE"));
  EXPECT_TRUE(contains(error_of([] { parse_change("injector_3=0@t=-1"); }), "SECONDS"));
  EXPECT_TRUE(contains(error_of([] { parse_change("injector_3=2@t=1"); }), "out of range"));
  // "h_s" alone is unique (alt.h_s); "rpm" too; an ambiguous bare name is refused.
  EXPECT_EQ(parse_change("h_s=3@t=1").param, P::kAltH);
  EXPECT_TRUE(contains(error_of([] { parse_change("d_pu=5@t=1"); }), "ambiguous"));
}

TEST(PlantConfig, RampedFaultStringsParse) {
  const TimedChange c = parse_change("engine.injectors_out=2@t=600,ramp=1800");
  EXPECT_EQ(c.param, P::kEngInjectorsOut);
  EXPECT_EQ(c.value, 2.0);
  EXPECT_EQ(c.time_s, 600.0);
  EXPECT_EQ(c.ramp_s, 1800.0);
  EXPECT_EQ(parse_change("op.power_kw=3800@t=600").ramp_s, 0.0);  // abrupt
  EXPECT_EQ(parse_change("op.power_kw=3800@t=600,ramp=0").ramp_s, 0.0);
  EXPECT_EQ(parse_change("meas.offset_kw=-12.5@t=3,ramp=0.5").value, -12.5);
  EXPECT_EQ(parse_change("op.grid_connected=0@t=3,ramp=0").ramp_s, 0.0);  // abrupt is fine
}

TEST(PlantConfig, MalformedRampsAreRejectedWithTheFaultString) {
  for (const char* bad : {"op.power_kw=3800@t=600,ramp=", "op.power_kw=3800@t=600,ramp=-5",
                          "op.power_kw=3800@t=600,rmp=5", "op.power_kw=3800@t=600,ramp=5s",
                          "op.power_kw=3800@t=600,"}) {
    const auto msg = error_of([&] { parse_change(bad); });
    EXPECT_TRUE(contains(msg, std::string("'") + bad + "'")) << msg;
    EXPECT_TRUE(contains(msg, "expected ',ramp=SECONDS'")) << msg;
  }
  const auto msg = error_of([] { parse_change("op.grid_connected=0@t=3,ramp=5"); });
  EXPECT_TRUE(contains(msg, "op.grid_connected takes abrupt changes only")) << msg;
  EXPECT_TRUE(contains(error_of([] { parse_change("engine.cylinders=6@t=3,ramp=5"); }),
                       "abrupt changes only"));
  EXPECT_TRUE(contains(error_of([] { parse_change("op.power_kw=3800@t=x,ramp=5"); }), "SECONDS"));
  EXPECT_TRUE(contains(error_of([] { parse_change("meas.offset_kw=2e5@t=1,ramp=5"); }),
                       "expected -100000 .. 100000 kW"));
}

TEST(PlantConfig, FractionalInjectorsOutCutsPartOfOneCylinder) {
  Params p;
  p.set(P::kEngInjectorsOut, 1.25, "test");
  p.set(P::kInjector2, 0.8, "test");
  EXPECT_EQ(p.injector(0), 0.0);                // cylinder 1 cut
  EXPECT_DOUBLE_EQ(p.injector(1), 0.75 * 0.8);  // cylinder 2 loses a quarter of its own fuel
  EXPECT_EQ(p.injector(2), 1.0);
  p.set(P::kEngInjectorsOut, 2.0, "test");
  EXPECT_EQ(p.injector(1), 0.0);
  EXPECT_EQ(p.injector(2), 1.0);
}

TEST(PlantConfig, ResolveSortsChangesByTime) {
  PlantOptions o;
  o.faults = {"alt.d_pu=5@t=3", "injector_1=0@t=1"};
  const ResolvedConfig r = resolve(o);
  ASSERT_EQ(r.changes.size(), 2u);
  EXPECT_EQ(r.changes[0].time_s, 1.0);
  EXPECT_EQ(r.changes[1].time_s, 3.0);
}

TEST(PlantConfig, WrittenTomlReadsBackIdentically) {
  Params p = preset("stornoway_island");
  p.set(P::kSolverRtol, 1.2345678901234567e-7, "test");
  EXPECT_TRUE(parse_toml(to_toml(p, "round trip"), "mem.toml") == p);
}

}  // namespace
}  // namespace plantsim
