// The condition monitor's core (DESIGN.md section 10; issue "condition monitoring"): pure,
// no I/O, one call per sample. The session's monitor phase feeds it every sample while the
// small permanent excitation runs, and every sample while it waits after a band trip.
//
//   learning   the first learn_s of excitation: the baseline's own spread of every
//              statistic (sequential_test.hpp), per block of block_samples
//   watching   per block: parity residual, single-parameter and joint fits of the tracked
//              parameters (block_analysis.hpp), the engine-order line; each standardised
//              statistic drives a two-sided CUSUM with a designed false-alarm rate
//   events     a level step in the raw power (1 s means leaving their recent range) or a band
//              trip: its shape is classified once event_post_s has been seen (event_shape.hpp);
//              a load change asks for a new baseline, a sensor step or a recovered power
//              loss becomes evidence, named after decision_blocks more blocks
//   alarms     a CUSUM crossing (or an event's evidence) is named by the signature table
//              (signatures.hpp); an alarm latches its cause, and the means are re-centred on
//              the new state (recentre_blocks) so that a further change is seen against it
//
// Memory is bounded: fixed buffers of one block plus warm-up, a 90 s event ring, and a
// few blocks of standardised values.
#pragma once

#include <cmath>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "rig/model/transfer_function.hpp"
#include "rig/monitor/amplitude_test.hpp"
#include "rig/monitor/block_analysis.hpp"
#include "rig/monitor/event_shape.hpp"
#include "rig/monitor/history.hpp"
#include "rig/monitor/mmfm_tracker.hpp"
#include "rig/monitor/sensor_test.hpp"
#include "rig/monitor/sequential_test.hpp"
#include "rig/monitor/signatures.hpp"
#include "rig/monitor/tracked_parameters.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::monitor {

struct MonitorSettings {
  double dt_s = 0.01;
  long block_samples = 2048;            // 20.48 s at 100 Hz: one value of every statistic
  long warmup_samples = 1024;           // the model's simulation settles on these before a block
  double coupling_rc_s = 1.6;           // matched AC coupling of excitation and response
  double learn_s = 600.0;               // baseline spread from this much excitation
  double false_alarms_per_month = 0.5;  // designed, all statistics together
  double cusum_k = 0.75;                // fastest detection for a 1.5 sigma shift
  int decision_blocks = 6;              // evidence gathered after an event before naming it
  int recentre_blocks = 20;  // after an alarm or a load change, the means follow the new state
  double tracking_forgetting = 0.8;  // per block, for the tracked-parameter trends
  double event_pre_s = 60.0;         // raw power kept before a level event / trip
  double event_post_s = 30.0;        // and seen after it before its shape is judged
  double level_sigmas = 8.0;         // 1 s mean beyond this many sigmas of its recent range
  double min_level_pct = 0.5;        // and beyond this % of P0: a level event
  // A level drift found by the level CUSUM is a load change when a load event or re-baseline
  // happened within this time (the governor's setpoint cannot be read), else a sensor drift.
  double load_event_memory_s = 1800.0;
  double p0_kw = 0.0;
};

struct MonitorEvent {
  double t_s = 0.0;
  std::string kind;  // "trip", "level", "load change", "sensor step", "power loss", "learnt"
  std::string text;
};

struct BlockReport {
  double t_s = 0.0;
  bool learning = false;
  std::vector<SeriesValue> values;
};

class Monitor {
 public:
  Monitor(const model::TransferFunction& baseline, const MonitorSettings& settings);

  // A sample while the excitation runs: applied excitation (%), raw power (kW), speed (rpm).
  std::optional<BlockReport> push(double t_s, double u_pct, double y_kw, double speed_rpm);
  // A sample outside the monitored excitation (ramp-down, waiting after a trip): the event
  // record only; u_pct is the applied bias change (0 at baseline).
  void observe(double t_s, double u_pct, double y_kw);
  // The supervisor tripped on the band at t_s.
  void trip(double t_s);
  // True once an event's shape has been judged and a new baseline (P0) is wanted: a trip,
  // or a level change seen while exciting. The caller re-baselines and calls resume().
  bool wants_rebaseline() const { return rebaseline_; }
  bool event_pending() const { return pending_.has_value(); }
  // A new segment at P0: couplers and the current block restart; learnt spreads are kept.
  void resume(double p0_kw);

  // Events and alarms since the last call (for the history, stdout and the live view).
  std::vector<MonitorEvent> take_events();
  std::vector<AlarmRecord> take_alarms();
  const std::vector<std::string>& parameter_names() const { return names_; }
  bool learning() const { return !learnt_; }
  double p0_kw() const { return s_.p0_kw; }
  const model::TransferFunction& baseline() const { return models_[0]; }
  // The share of the planned excitation to apply now (1, or a level of the amplitude test).
  double excitation_scale() const { return amp_ ? amp_->scale() : 1.0; }
  const CusumDesign& design() const { return design_; }
  long alarms() const { return alarm_count_; }

 private:
  struct Statistic {
    explicit Statistic(std::string n) : name(std::move(n)) {}
    std::string name;
    std::vector<double> learn;  // values while learning or re-centring
    Spread spread;
    Cusum cusum;
    std::deque<double> recent_z;
  };
  struct Pending {
    long detect_sample = 0;  // global sample index of the trip or level detection
    double t_s = 0.0;
    bool trip = false;
  };

  void restart_block();
  void forget_recent_block();
  void end_block(double t_s, BlockReport& report);
  std::vector<double> block_statistics(const BlockFit& f);
  void learn(const BlockFit& f, const std::vector<double>& x, double t_s);
  void finish_learning(double t_s, bool spreads);
  std::string learnt_text() const;
  void watch(const std::vector<double>& x, const BlockFit& f, double t_s);
  void alarm(double t_s, int onset_blocks, const std::string& trigger);
  void level_drift(const std::vector<double>& x, double t_s);
  void sensor_block(const BlockFit& f, double t_s);
  bool amplitude_block(const BlockFit& f, double t_s);
  double event_line_z(const std::vector<double>& record) const;
  Evidence evidence(int blocks) const;
  void level_check(double t_s, double y_kw);
  void judge_event(double t_s);
  void tracked_values(const BlockFit& f, BlockReport& report);
  std::vector<double> ring_copy(const std::vector<double>& ring) const;
  // The raw power of the ring without the excitation's predicted response (the baseline
  // model run on the ring's excitation): what is left is the event and the noise.
  std::vector<double> event_record() const;

  MonitorSettings s_;
  std::vector<model::TransferFunction> models_;
  std::vector<double> probes_;
  std::vector<std::string> names_;
  std::vector<const TrackedParameter*> params_;
  signal::AcCoupler cu_, cy_;
  bool coupler_primed_ = false;
  double y_ref_kw_ = 0.0;
  Eigen::VectorXd u_hist_;  // warm-up + block, coupled
  Eigen::VectorXd y_blk_;
  long in_block_ = 0, filled_ = 0;
  double speed_sum_ = 0.0;
  long speed_n_ = 0;
  // Statistics: one per tracked parameter (joint fit), then residual, then line.
  std::vector<Statistic> stats_;
  CusumDesign design_;
  bool learnt_ = false;
  int learn_blocks_ = 0, recentre_left_ = 0;
  Eigen::MatrixXd track_a_;
  Eigen::VectorXd track_b_;
  std::vector<double> mean_dev_;              // learnt mean of each joint deviation (raw units)
  std::vector<double> dev_sum_, dev_weight_;  // its weighted mean while learning
  std::vector<std::vector<double>> raw_dev_, raw_se_;
  std::deque<Eigen::VectorXd> recent_explained_;
  std::optional<BlockFit> last_fit_;
  std::vector<double> tracked_display_;
  bool load_changed_ = false;
  double centred_p0_kw_ = 0.0;  // P0 when the means were last centred
  bool recentre_all_ = false;   // the running re-centring follows an alarm (not a load change)
  // Events.
  std::vector<double> ring_;    // raw power, circular
  std::vector<double> ring_u_;  // applied excitation of the same samples
  long sample_ = 0;             // global sample index (samples pushed or observed)
  double sec_sum_ = 0.0;
  long sec_n_ = 0;
  std::deque<double> sec_means_;
  std::vector<double> sec_learn_;
  double sec_sigma_ = 0.0;
  int level_hits_ = 0;
  std::optional<Pending> pending_;
  std::optional<EventShape> shape_;  // the latest fault-shaped event, as evidence
  double shape_level_ratio_ = 0.0;
  int decide_in_ = -1;                // blocks until an event's evidence is named
  std::optional<SensorTest> sensor_;  // a measured level moved: gain error or offset?
  std::optional<AmplitudeTest> amp_;  // a phase lag: backlash or dead time?
  double amp_z_ = NAN;                // the last amplitude test's verdict, as evidence
  double sensor_z_gain_ = NAN, sensor_z_offset_ = NAN;
  std::optional<std::pair<std::string, int>> deferred_;  // a crossing awaiting confirmation
  bool rebaseline_ = false;
  std::set<std::string> latched_;
  long alarm_count_ = 0;
  std::vector<MonitorEvent> events_;
  std::vector<AlarmRecord> alarms_;
  // The measured level against the last baseline (block means), for slow drifts.
  Statistic level_{"level"};
  double level_ref_kw_ = 0.0;
  double last_load_event_s_ = -1e30;  // a load change or re-baseline
  double speed_rpm_ = 0.0;            // latest, for the engine cycle
  MmfmTracker mmfm_;                  // the thesis's view of the same transfer function
  double block_level_kw_ = 0.0;       // mean raw power of the latest block
  double event_line_z_ = 0.0;         // the line in the latest event's record
};

}  // namespace rig::monitor
