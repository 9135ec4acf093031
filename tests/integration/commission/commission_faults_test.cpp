// Faults during a commissioning test: the exit code says what happened, the bias is back at
// baseline, and the recording stays readable. Malformed test files are refused before
// anything is written.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iterator>
#include <regex>
#include <thread>

#include "rig/io/recording.hpp"
#include "tests/integration/commission/run_rig.hpp"

namespace rig::testing {
namespace {

using namespace std::chrono_literals;

// A process started through the shell with its pid captured, output to `log`.
struct Background {
  pid_t pid = -1;
  std::filesystem::path log;
  static Background start(const std::string& cmd, const std::filesystem::path& log) {
    const auto pid_file = log.string() + ".pid";
    const std::string line =
        fmt::format("( {} ) > {} 2>&1 & echo $! > {}", cmd, log.string(), pid_file);
    EXPECT_EQ(std::system(line.c_str()), 0);
    Background b;
    b.log = log;
    b.pid = std::stoi(read_text(pid_file));
    return b;
  }
  // Waits until the process is gone (it is the shell's child, reaped by init).
  bool wait_gone(std::chrono::seconds limit) const {
    for (auto t = 0ms; t < limit; t += 100ms) {
      if (kill(pid, 0) != 0) return true;
      std::this_thread::sleep_for(100ms);
    }
    return false;
  }
};

// plantsim on the monotonic clock, Modbus TCP on an ephemeral port; returns the rig's URI.
std::string start_realtime_plant(const std::filesystem::path& dir, Background& plant) {
  plant = Background::start((bin_dir() / "plantsim").string() +
                                " --preset stornoway --seed 3 --clock realtime "
                                "--modbus tcp://127.0.0.1:0",
                            dir / "plantsim.log");
  const std::regex ready("modbus tcp://127\\.0\\.0\\.1:([0-9]+) ready");
  for (int i = 0; i < 100; ++i) {
    std::smatch m;
    const std::string text = read_text(dir / "plantsim.log");
    if (std::regex_search(text, m, ready))
      return "modbus+tcp://127.0.0.1:" + m[1].str() + "?unit=1";
    std::this_thread::sleep_for(100ms);
  }
  ADD_FAILURE() << "plantsim did not start: " << read_text(dir / "plantsim.log");
  return {};
}

// Lines of a recording being written (the header included); 0 while it does not exist.
std::size_t recorded_rows(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  return static_cast<std::size_t>(
      std::count(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>(), '\n'));
}

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

constexpr const char* kRealtimeProfile = R"([steady_state]
duration_s = 3.0
[pilot]
duration_s = 20.0
)";

TEST(CommissionFaults, GridVoltageDipTripsWithExit4AndBiasAtBaseline) {
  const auto out = fresh_dir("dip");
  const int code = run_rig(
      "commission --emulate --seed 1 --quiet --fault grid.v_pu=0.85@t=80 --out " + out.string(),
      log_beside(out));
  EXPECT_EQ(code, 4) << read_text(log_beside(out));
  const auto report = read_json(out / "report.json");
  EXPECT_EQ(report["safety"]["trip"]["cause"], "out_of_band");
  const auto rec = io::read_recording(out / "recording.csv");
  ASSERT_GT(rec.rows(), 1000);
  const auto& u = rec.column("u");
  const auto& echo = rec.column("bias_echo");
  EXPECT_DOUBLE_EQ(u(rec.rows() - 1), 0.0) << "bias not back at baseline";
  EXPECT_DOUBLE_EQ(echo(rec.rows() - 1), 0.0) << "governor still applies a bias";
}

TEST(CommissionFaults, MalformedTestFilesExit2BeforeAnythingIsWritten) {
  const auto dir = fresh_dir("malformed");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"[excitation]\nbandwith_hz = 4\n", "excitation.bandwith_hz"},
      {"[mmfm]\nlags = \"many\"\n", "mmfm.lags"},
      {"[safety]\nband_pct = 4.0\n", "safety.band_pct"},
      {"[sweep]\nto_hz = 80.0\n", "sweep.to_hz"},
      {"[link\n", "line 1"}};
  int i = 0;
  for (const auto& [text, key] : cases) {
    const auto out = dir / std::to_string(i);
    const auto test = write_file(dir / fmt::format("t{}.toml", i++), text);
    const int code =
        run_rig(fmt::format("commission --emulate --test {} --out {}", test.string(), out.string()),
                dir / "rig.log");
    const std::string log = read_text(dir / "rig.log");
    EXPECT_EQ(code, 2) << log;
    EXPECT_NE(log.find(key), std::string::npos) << log;
    EXPECT_FALSE(std::filesystem::exists(out / "recording.csv")) << "started despite " << key;
  }
}

// DESIGN.md section 4: an --out that is a file, is not writable or holds an earlier run's
// files is exit 2 before plantsim starts (no plantsim.log) or the governor is touched; --force
// clears an earlier run first, so none of its files stay beside the new ones.
TEST(CommissionFaults, UnusableOrEarlierOutExits2AndForceClearsIt) {
  const auto dir = fresh_dir("out-rules");
  const auto file = write_file(dir / "a-file", "x\n");
  for (const auto& [out, expected] : std::vector<std::pair<std::filesystem::path, std::string>>{
           {file, "exists and is not a folder"}, {file / "sub", "cannot create the folder"}}) {
    const int code = run_rig("commission --emulate --quiet --out " + out.string(), dir / "rig.log");
    const std::string log = read_text(dir / "rig.log");
    EXPECT_EQ(code, 2) << log;
    EXPECT_NE(log.find(expected), std::string::npos) << log;
  }
  // An earlier run's files: refused, nothing of them touched.
  const auto earlier = dir / "earlier";
  std::filesystem::create_directories(earlier);
  write_file(earlier / "model.json", "{\"type\":\"tf\",\"num\":[1],\"den\":[1],\"delay_s\":0}\n");
  write_file(earlier / "h1.csv", "freq_hz,mag,phase_deg,coherence\n");
  int code = run_rig("commission --emulate --quiet --out " + earlier.string(), dir / "rig.log");
  EXPECT_EQ(code, 2) << read_text(dir / "rig.log");
  EXPECT_NE(read_text(dir / "rig.log").find("--force"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(earlier / "plantsim.log"));
  EXPECT_TRUE(std::filesystem::exists(earlier / "model.json"));
  // With --force and a test that cannot produce a model (a 1 s excitation cannot reach the
  // applied share the test demands), the old model.json and h1.csv are gone.
  const auto test = write_file(dir / "nomodel.toml",
                               "[steady_state]\nduration_s = 3.0\n[pilot]\nduration_s = 3.0\n"
                               "[mmfm]\nmin_duration_s = 21.0\nmax_duration_s = 21.0\n"
                               "min_applied_fraction = 1.0\n[sweep]\nenabled = false\n");
  code = run_rig(
      "commission --emulate --quiet --force --test " + test.string() + " --out " + earlier.string(),
      dir / "rig.log");
  EXPECT_EQ(code, 1) << read_text(dir / "rig.log");
  EXPECT_FALSE(std::filesystem::exists(earlier / "model.json"));
  EXPECT_FALSE(std::filesystem::exists(earlier / "h1.csv") &&
               read_text(earlier / "h1.csv") == "freq_hz,mag,phase_deg,coherence\n");
  const auto report = read_json(earlier / "report.json");
  EXPECT_EQ(report["model_written"], false);
  EXPECT_NE(report["model_rejected"].get<std::string>().find("applied excitation"),
            std::string::npos);
}

// A disk that fills is a failure of the rig itself: a supervisor trip with its own cause, the
// bias ramped down and the enable cleared, exit 4, and a recording that still reads. The limit
// is the file-size limit of the rig's process (`ulimit -f`, in kB).
void expect_full_disk_trip(const std::filesystem::path& dir, long limit_kb) {
  const auto out = dir / "out";
  const auto test = write_file(dir / "t.toml",
                               "[steady_state]\nduration_s = 3.0\n[pilot]\nduration_s = 5.0\n"
                               "[sweep]\nenabled = false\n");
  const std::string cmd =
      fmt::format("bash -c 'ulimit -f {}; exec {} commission --emulate --quiet --test {} --out {}'",
                  limit_kb, (bin_dir() / "rig").string(), test.string(), out.string());
  const int status = std::system((cmd + " > " + (dir / "rig.log").string() + " 2>&1").c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "killed: " << read_text(dir / "rig.log");
  EXPECT_EQ(WEXITSTATUS(status), 4) << read_text(dir / "rig.log");
  const auto report = read_json(out / "report.json");
  // Every exit 4 names its cause in the report; print the log and the report when it does not.
  ASSERT_TRUE(report["safety"]["trip"].is_object())
      << read_text(dir / "rig.log") << "\nsafety: " << report["safety"].dump()
      << "\nphases: " << report.value("phases", nlohmann::json()).dump();
  EXPECT_EQ(report["safety"]["trip"]["cause"], "rig_failure");
  EXPECT_EQ(report["ramp_down"]["cleared"], true);
  EXPECT_EQ(report["model_written"], false);
  EXPECT_FALSE(std::filesystem::exists(out / "model.json"));
  const auto rec = io::read_recording(out / "recording.csv");  // whole rows only
  EXPECT_GT(rec.rows(), 1000);
  const std::string text = read_text(out / "recording.csv");
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  const auto sidecar = read_json(out / "recording.json");
  EXPECT_EQ(sidecar["complete"], false);
  EXPECT_EQ(sidecar["rows"].get<long>(), static_cast<long>(rec.rows()));
}

// Mid-test: 150 kB, about 22 s of the 53 s test's rows (some 69 bytes a row at 100 Hz), so
// the recorder's flusher meets the limit with most of the test still to run. (At 300 kB the
// limit fell in the last 15 % of an emulated test that runs in 2.4 s of wall time, and under
// load the flusher sometimes first met it when the recording was closed.)
TEST(CommissionFaults, FullDiskMidTestIsARigFailureTripExit4) {
  expect_full_disk_trip(fresh_dir("disk-full"), 150);
}

// In the last rows: a limit 2 kB under the whole recording's size (measured by a first run),
// which the flusher may meet only when the recording is closed at the end of the test: the
// same rig failure, named as that trip (the bias already back at its baseline).
TEST(CommissionFaults, FullDiskInTheLastRowsIsTheSameRigFailureTrip) {
  const auto dir = fresh_dir("disk-full-last");
  const auto whole = dir / "whole";
  const auto test = write_file(dir / "t.toml",
                               "[steady_state]\nduration_s = 3.0\n[pilot]\nduration_s = 5.0\n"
                               "[sweep]\nenabled = false\n");
  ASSERT_EQ(
      run_rig("commission --emulate --quiet --test " + test.string() + " --out " + whole.string(),
              dir / "whole.log"),
      0)
      << read_text(dir / "whole.log");
  const auto size_kb =
      static_cast<long>(std::filesystem::file_size(whole / "recording.csv") / 1024);
  expect_full_disk_trip(dir, size_kb - 2);
}

TEST(CommissionFaults, LinkDropMidTestExit3AndRecordingReadable) {
  const auto dir = fresh_dir("drop");
  Background plant;
  const std::string uri = start_realtime_plant(dir, plant);
  ASSERT_FALSE(uri.empty());
  const auto test = write_file(dir / "rt.toml", kRealtimeProfile);
  const Background rig = Background::start(
      fmt::format("{}; echo $? > {}",
                  (bin_dir() / "rig").string() + " commission --quiet --link " + uri + " --test " +
                      test.string() + " --out " + (dir / "out").string(),
                  (dir / "code").string()),
      dir / "rig.log");
  // Kill the plant once the rig has recorded 6 s (steady state done, pilot under way),
  // whatever the rig's start-up took on this machine.
  const auto recording = dir / "out/recording.csv";
  for (int i = 0; i < 300 && recorded_rows(recording) < 600; ++i) {
    std::this_thread::sleep_for(100ms);
  }
  kill(plant.pid, SIGKILL);
  rig.wait_gone(30s);
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(read_text(dir / "code"), "3\n") << read_text(dir / "rig.log");
  const auto rec = io::read_recording(recording);
  EXPECT_GT(rec.rows(), 500) << read_text(dir / "rig.log");
}

TEST(CommissionFaults, OperatorAbortRampsDownAndKill9KeepsTheRecording) {
  const auto dir = fresh_dir("abort");
  Background plant;
  const std::string uri = start_realtime_plant(dir, plant);
  ASSERT_FALSE(uri.empty());
  const auto test = write_file(dir / "rt.toml", kRealtimeProfile);
  const std::string rig_cmd = (bin_dir() / "rig").string() + " commission --quiet --link " + uri +
                              " --test " + test.string() + " --out ";
  // SIGINT: clean ramp-down, exit 4 (safety abort), bias back at baseline.
  const Background a =
      Background::start(fmt::format("exec {}", rig_cmd + (dir / "a").string()), dir / "a.log");
  std::this_thread::sleep_for(7s);
  kill(a.pid, SIGINT);
  a.wait_gone(30s);
  const auto report = read_json(dir / "a/report.json");
  EXPECT_EQ(report["exit_code"], 4) << read_text(dir / "a.log");
  EXPECT_EQ(report["safety"]["trip"]["cause"], "external");
  const auto rec = io::read_recording(dir / "a/recording.csv");
  EXPECT_DOUBLE_EQ(rec.column("u")(rec.rows() - 1), 0.0);
  // kill -9: the recording holds every row up to the last flush and reads back.
  const Background b =
      Background::start(fmt::format("exec {}", rig_cmd + (dir / "b").string()), dir / "b.log");
  std::this_thread::sleep_for(6s);
  kill(b.pid, SIGKILL);
  b.wait_gone(10s);
  const auto cut = io::read_recording(dir / "b/recording.csv");
  EXPECT_GT(cut.rows(), 300);  // >= 5 s at 100 Hz, flushed at least every 0.5 s
  kill(plant.pid, SIGTERM);
}

// DESIGN.md section 4: an emulated plant is never left running, even when the rig is killed
// with no chance to stop it (plantsim --exit-with-parent).
TEST(CommissionFaults, KilledEmulatingRigLeavesNoPlantRunning) {
  const auto dir = fresh_dir("kill-emulate");
  const Background rig = Background::start(
      fmt::format("exec {} commission --emulate --clock realtime --quiet --out {}",
                  (bin_dir() / "rig").string(), (dir / "out").string()),
      dir / "rig.log");
  // The plant is the rig's child; wait until it is up.
  pid_t plant = -1;
  for (int i = 0; i < 100 && plant < 0; ++i) {
    std::this_thread::sleep_for(100ms);
    const std::string children =
        read_text(fmt::format("/proc/{}/task/{}/children", rig.pid, rig.pid));
    if (!children.empty()) plant = std::stoi(children);
  }
  ASSERT_GT(plant, 0) << "no plantsim child: " << read_text(dir / "rig.log");
  ASSERT_EQ(kill(plant, 0), 0);
  kill(rig.pid, SIGKILL);
  ASSERT_TRUE(rig.wait_gone(10s));
  bool gone = false;
  for (int i = 0; i < 50 && !gone; ++i) {
    std::this_thread::sleep_for(100ms);
    // Gone, or a zombie waiting for init to reap it.
    const std::string stat = read_text(fmt::format("/proc/{}/stat", plant));
    gone = stat.empty() || stat.find(") Z ") != std::string::npos;
  }
  EXPECT_TRUE(gone) << "plantsim " << plant << " still running after the rig was killed";
  if (!gone) kill(plant, SIGKILL);
}

}  // namespace
}  // namespace rig::testing
