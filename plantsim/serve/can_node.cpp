#include "plantsim/serve/can_node.hpp"

#include <fmt/format.h>
#include <poll.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "drivers/can/j1939.hpp"

namespace plantsim::serve {
namespace j1939 = drivers::j1939;
namespace {

constexpr std::chrono::milliseconds kEec1Period{20};
constexpr std::chrono::milliseconds kGtacpPeriod{100};
constexpr std::size_t kMaxPendingEchoes = 16;  // a flood between two ticks answers the last 16

// True when the tick that ended at plant time t crossed a multiple of `period`.
bool due(const GovernorSnapshot& s, std::chrono::nanoseconds tick,
         std::chrono::nanoseconds period) {
  return (s.plant_time / period) != ((s.plant_time - tick) / period);
}

// Power bytes 0-3 = 0xFFFFFFFF, J1939's "not available". PGN 0xFF51 carries a checksum over
// its data (byte 7: counter high nibble, checksum low nibble), so it is resealed.
void mark_power_not_available(can_frame& f, bool sealed) {
  for (int i = 0; i < 4; ++i) f.data[i] = 0xFF;
  if (!sealed) return;
  const auto counter = static_cast<std::uint8_t>(f.data[7] >> 4);
  f.data[7] = static_cast<std::uint8_t>((counter << 4) |
                                        j1939::checksum4(f.data, counter, f.can_id & CAN_EFF_MASK));
}

}  // namespace

drivers::LinkResult<std::unique_ptr<CanNode>> CanNode::open(const drivers::LinkUri& endpoint,
                                                            Governor& governor, ClockMode clock,
                                                            CanNodeOptions options) {
  auto ep = drivers::can::open_can_endpoint(endpoint, drivers::can::CanRole::kNode);
  if (!ep) return ep.error();
  const std::string name = endpoint.scheme == drivers::LinkScheme::kCanUdp
                               ? fmt::format("udp://{}:{}", endpoint.host, ep.value()->local_port())
                               : fmt::format("socketcan:{}", endpoint.device);
  std::unique_ptr<CanNode> node(new CanNode(std::move(ep.value()), governor, clock, options, name));
  CanNode* raw = node.get();
  governor.add_tick_listener([raw](const GovernorSnapshot& s) { raw->on_tick(s); });
  return node;
}

CanNode::CanNode(std::unique_ptr<drivers::can::CanEndpoint> ep, Governor& governor, ClockMode clock,
                 CanNodeOptions options, std::string endpoint)
    : ep_(std::move(ep)),
      governor_(governor),
      clock_(clock),
      options_(options),
      endpoint_(std::move(endpoint)),
      synchronous_rpm_(governor.snapshot().measurement.speed_rpm) {}

CanNode::~CanNode() { stop(); }

void CanNode::start() {
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void CanNode::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

std::optional<drivers::LinkError> CanNode::failure() const {
  std::lock_guard lock(mu_);
  return failure_;
}

CanCounters CanNode::counters() const {
  std::lock_guard lock(mu_);
  return counters_;
}

// poll() outside the lock, then a zero-timeout receive under it: the tick listener (another
// thread in realtime) may send on the same endpoint meanwhile.
void CanNode::run() {
  const int fd = ep_->fd();
  while (!stop_) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    // Everything queued is handled before polling again (a rig sends command + lockstep).
    while (!stop_) {
      std::optional<can_frame> frame;
      {
        std::lock_guard lock(mu_);
        auto r = ep_->receive(std::chrono::milliseconds(0));
        if (r) {
          frame = r.value();
        } else if (r.error().kind == drivers::LinkErrorKind::kLinkLost) {
          failure_ = r.error();
          return;
        } else if (r.error().kind == drivers::LinkErrorKind::kTimeout) {
          break;
        } else {
          ++counters_.bad_checksum;  // a datagram that is not a can_frame
        }
      }
      // serve.drop_link: frames are taken off the socket and ignored (nobody listens).
      if (frame && !governor_.snapshot().link_dropped) handle(*frame);
    }
  }
}

// The governor takes commands only from the configured rig address; TSC1 (PDU1) only when
// addressed to the governor or to all.
bool CanNode::from_rig(const can_frame& frame) {
  const auto id = j1939::decode_id(frame.can_id & CAN_EFF_MASK);
  const bool ours =
      id.destination == j1939::kGovernorAddress || id.destination == j1939::kGlobalAddress;
  if (id.source == options_.rig_address && ours) return true;
  std::lock_guard lock(mu_);
  ++counters_.wrong_source;
  return false;
}

void CanNode::handle(const can_frame& frame) {
  const std::uint32_t pgn = j1939::pgn_of(frame);
  {
    std::lock_guard lock(mu_);
    ++counters_.received;
  }
  const bool command =
      pgn == j1939::kPgnRigCommand || pgn == j1939::kPgnTsc1 || pgn == j1939::kPgnLockstep;
  if (command && !from_rig(frame)) return;
  if (pgn == j1939::kPgnRigCommand) return handle_command(frame);
  if (pgn == j1939::kPgnTsc1) return handle_tsc1(frame);
  if (pgn == j1939::kPgnLockstep && clock_ == ClockMode::kLockstep) return handle_lockstep(frame);
  std::lock_guard lock(mu_);
  ++counters_.ignored;
}

void CanNode::handle_command(const can_frame& frame) {
  auto m = j1939::decode_rig_command(frame);  // checksum only; the counter is checked here
  {
    std::lock_guard lock(mu_);
    if (!m) {
      ++counters_.bad_checksum;
      return;
    }
    const bool in_sequence = !command_counter_ || m->counter == ((*command_counter_ + 1) & 0x0F);
    command_counter_ = m->counter;
    if (!in_sequence) {
      ++counters_.bad_counter;
      return;
    }
    ++counters_.accepted;
  }
  governor_.set_bias_pct(m->bias_pct);
  if (!m->keep_enable) governor_.set_enable(m->enable);
  governor_.heartbeat(CommandSource::kCan, m->counter);
  command_accepted(m->counter, m->bias_pct);
}

void CanNode::handle_tsc1(const can_frame& frame) {
  std::optional<std::uint8_t> previous;
  {
    std::lock_guard lock(mu_);
    previous = tsc1_counter_;
  }
  auto m = j1939::decode_tsc1(frame, previous);
  {
    std::lock_guard lock(mu_);
    if (!m) {
      const bool counter_error = m.error().kind == drivers::LinkErrorKind::kChecksum &&
                                 j1939::decode_tsc1(frame).has_value();
      ++(counter_error ? counters_.bad_counter : counters_.bad_checksum);
      if (counter_error) tsc1_counter_ = frame.data[7] & 0x0F;
      return;
    }
    tsc1_counter_ = m->counter;
    ++counters_.accepted;
  }
  const double bias_pct =
      m->release ? 0.0 : 100.0 * (m->speed_rpm - synchronous_rpm_) / synchronous_rpm_;
  governor_.set_bias_pct(bias_pct);
  governor_.set_enable(!m->release);
  governor_.heartbeat(CommandSource::kTsc1, m->counter);
  command_accepted(m->counter, bias_pct);
}

// After the governor took the command, so that the echo's tick is one that applies it.
void CanNode::command_accepted(std::uint8_t counter, double received_pct) {
  std::lock_guard lock(mu_);
  if (pending_echoes_.size() == kMaxPendingEchoes) pending_echoes_.erase(pending_echoes_.begin());
  pending_echoes_.push_back({counter, received_pct});
}

void CanNode::handle_lockstep(const can_frame& frame) {
  auto m = j1939::decode_lockstep(frame);
  {
    std::lock_guard lock(mu_);
    ++(m ? counters_.accepted : counters_.bad_checksum);
  }
  if (!m) return;
  governor_.advance(m->ticks);
  // The snapshot before taking mu_: the tick listener takes the governor's lock, then mu_.
  const GovernorSnapshot s = governor_.snapshot();
  std::lock_guard lock(mu_);
  if (ep_->has_peer() && !s.link_dropped) send_sample_locked(s);
}

void CanNode::on_tick(const GovernorSnapshot& s) {
  std::lock_guard lock(mu_);
  if (!ep_->has_peer() || s.link_dropped) return;
  const bool answered = !pending_echoes_.empty();
  send_echoes_locked(s);
  const auto tick = governor_.tick_period();
  if (clock_ == ClockMode::kRealtime) {
    const auto period = options_.sample_period;
    if (period.count() > 0 ? due(s, tick, period) : answered) send_sample_locked(s);
  }
  const auto& m = s.measurement;
  if (due(s, tick, kEec1Period)) {
    // Torque in % of rated: P = T w, so T/T_rated = (P/P_rated) (w_rated/w).
    const double torque_pct = m.speed_rpm > 0.0 ? 100.0 * m.power_w / governor_.rated_power_w() *
                                                      (synchronous_rpm_ / m.speed_rpm)
                                                : 0.0;
    const bool overridden = (s.status & drivers::kBiasActive) != 0;
    send_locked(j1939::encode_eec1(
        j1939::Eec1{m.speed_rpm, std::clamp(torque_pct, -125.0, 125.0),
                    overridden ? options_.rig_address : j1939::kGovernorAddress}));
  }
  if (due(s, tick, kGtacpPeriod)) {
    can_frame gtacp = j1939::encode_gtacp(j1939::Gtacp{m.power_w, 0.0});
    if (s.power_invalid || !std::isfinite(m.power_w)) mark_power_not_available(gtacp, false);
    send_locked(gtacp);
  }
}

void CanNode::send_echoes_locked(const GovernorSnapshot& s) {
  for (const auto& e : pending_echoes_) {
    send_locked(j1939::encode_bias_echo(
        j1939::BiasEcho{s.bias_applied_pct, e.received_pct, s.counter(),
                        static_cast<std::uint8_t>(s.status & 0xFF), e.counter}));
  }
  pending_echoes_.clear();
}

void CanNode::send_sample_locked(const GovernorSnapshot& s) {
  const auto& m = s.measurement;
  can_frame sample = j1939::encode_plant_sample(
      j1939::PlantSample{m.power_w, s.counter(), static_cast<std::uint8_t>(s.status & 0xFF)});
  if (s.power_invalid || !std::isfinite(m.power_w)) mark_power_not_available(sample, true);
  send_locked(sample);
}

void CanNode::send_locked(const can_frame& frame) {
  if (ep_->send(frame)) {
    ++counters_.sent;
  } else {
    ++counters_.send_failed;  // a full queue drops a sample, as a real bus would
  }
}

}  // namespace plantsim::serve
