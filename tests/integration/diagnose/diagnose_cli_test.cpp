// `rig diagnose` end to end through the command-line parser: files written, exit codes,
// one-line errors for bad input.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "concealed.hpp"
#include "rig/cli/commands.hpp"
#include "rig/cli/diagnose.hpp"
#include "rig/model/model_file.hpp"

namespace fs = std::filesystem;

namespace {

class DiagnoseCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rig_diagnose_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes rec.csv (t,u,y) and its sidecar, and model.json.
  void write_case(const rig::diagnose::ConcealedRecording& rec, const std::string& sidecar = "") {
    std::ofstream csv(dir_ / "rec.csv");
    csv << "t,u,y\n";
    csv.precision(12);
    for (Eigen::Index k = 0; k < rec.input.u.size(); ++k)
      csv << static_cast<double>(k) * rec.input.dt_s << ',' << rec.input.u(k) << ','
          << rec.input.y(k) << '\n';
    if (!sidecar.empty()) std::ofstream(dir_ / "rec.json") << sidecar;
    rig::model::ModelFile m;
    m.tf = rec.input.model;
    m.units = {{"input", "% of rated power"}, {"output", "kW"}};
    rig::model::write_model(dir_ / "model.json", m);
  }

  int run(std::vector<std::string> args) {
    CLI::App app{"rig"};
    app.require_subcommand(1);
    rig::cli::add_diagnose_command(app);
    args.insert(args.begin(), {"rig", "diagnose"});
    std::vector<char*> argv;
    for (auto& s : args) argv.push_back(s.data());
    return rig::cli::run_app(app, static_cast<int>(argv.size()), argv.data());
  }

  std::vector<std::string> std_args() {
    return {"--recording", (dir_ / "rec.csv").string(), "--model", (dir_ / "model.json").string(),
            "--out",       (dir_ / "out").string()};
  }

  fs::path dir_;
};

rig::diagnose::ConcealedRecording make(std::optional<rig::diagnose::Effect> e,
                                       double duration_s = 120.0) {
  rig::diagnose::ConcealedSpec spec;
  spec.effect = e;
  spec.seed = 77;
  spec.duration_s = duration_s;
  return rig::diagnose::make_concealed(spec);
}

TEST_F(DiagnoseCli, WritesReportsAndTheAugmentedModel) {
  write_case(make(rig::diagnose::Effect::kDeadTime), R"({"units": {"u": "%", "y": "kW"}})");
  ASSERT_EQ(run(std_args()), 0);
  std::ifstream in(dir_ / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["verdict"], "dead_time");
  EXPECT_TRUE(fs::exists(dir_ / "out" / "report.html"));
  const auto aug = rig::model::read_model(dir_ / "out" / "augmented_model.json");
  EXPECT_NEAR(aug.tf.delay_s, 0.10, 0.02);
}

TEST_F(DiagnoseCli, NullCaseIsNone) {
  write_case(make(std::nullopt));
  ASSERT_EQ(run(std_args()), 0);
  std::ifstream in(dir_ / "out" / "report.json");
  EXPECT_EQ(nlohmann::json::parse(in)["verdict"], "none");
}

// A freq_hz column is read by default (a constant one: nothing taken out, said in
// report.json); --bus-frequency none ignores it; a named column that is not there is a
// one-line input error.
TEST_F(DiagnoseCli, ReadsTheBusFrequencyColumn) {
  const auto rec = make(std::nullopt);
  {
    std::ofstream csv(dir_ / "rec.csv");
    csv << "t,u,y,freq_hz\n";
    csv.precision(12);
    for (Eigen::Index k = 0; k < rec.input.u.size(); ++k)
      csv << static_cast<double>(k) * rec.input.dt_s << ',' << rec.input.u(k) << ','
          << rec.input.y(k) << ",50.000\n";
    rig::model::ModelFile m;
    m.tf = rec.input.model;
    rig::model::write_model(dir_ / "model.json", m);
  }
  const auto report = [&] {
    std::ifstream in(dir_ / "out" / "report.json");
    return nlohmann::json::parse(in);
  };
  ASSERT_EQ(run(std_args()), 0);
  nlohmann::json j = report();
  EXPECT_EQ(j["verdict"], "none");
  ASSERT_TRUE(j["bus_frequency"].is_object());
  EXPECT_FALSE(j["bus_frequency"]["used"].get<bool>());
  EXPECT_EQ(j["bus_frequency"]["frequency_rms_hz"].get<double>(), 0.0);
  auto args = std_args();
  args.insert(args.end(), {"--bus-frequency", "none", "--force"});
  ASSERT_EQ(run(args), 0);
  EXPECT_TRUE(report()["bus_frequency"].is_null());
  args = std_args();
  args.insert(args.end(), {"--bus-frequency", "grid_hz", "--force"});
  testing::internal::CaptureStderr();
  EXPECT_EQ(run(args), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("grid_hz"), std::string::npos) << err;
}

TEST_F(DiagnoseCli, BadInputExitsTwo) {
  write_case(make(std::nullopt, 30.0), R"({"units": {"u": "%", "y": "MW"}})");
  EXPECT_EQ(run(std_args()), 2);  // output unit differs from the model's
  write_case(make(std::nullopt, 30.0), R"({"sample_rate_hz": 50})");
  EXPECT_EQ(run(std_args()), 2);  // sidecar rate differs from the time column
  std::ofstream(dir_ / "plant.toml") << "preset = \"stornoway\"\n";
  auto args = std_args();
  args[3] = (dir_ / "plant.toml").string();
  EXPECT_EQ(run(args), 2);
  std::ofstream(dir_ / "rec.json") << "{}";
  std::ofstream(dir_ / "short.csv") << "t,u,y\n0,1,2\n0.01,2,3\n0.02,1,2\n";
  args = std_args();
  args[1] = (dir_ / "short.csv").string();
  EXPECT_EQ(run(args), 2);
  std::ofstream(dir_ / "model.json") << R"({"type":"tf","num":[1],"den":[1,-1]})";
  EXPECT_EQ(run(std_args()), 2);  // unstable model
}

}  // namespace
