#include "plantsim/serve/can_node.hpp"

#include <fmt/format.h>
#include <poll.h>

#include <algorithm>
#include <cmath>

#include "drivers/can/j1939.hpp"

namespace plantsim::serve {
namespace j1939 = drivers::j1939;
namespace {

constexpr std::chrono::milliseconds kEec1Period{20};
constexpr std::chrono::milliseconds kGtacpPeriod{100};

// True when the tick that ended at plant time t crossed a multiple of `period`.
bool due(const GovernorSnapshot& s, std::chrono::nanoseconds tick,
         std::chrono::milliseconds period) {
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
                                                            Governor& governor, ClockMode clock) {
  auto ep = drivers::can::open_can_endpoint(endpoint, drivers::can::CanRole::kNode);
  if (!ep) return ep.error();
  const std::string name = endpoint.scheme == drivers::LinkScheme::kCanUdp
                               ? fmt::format("udp://{}:{}", endpoint.host, ep.value()->local_port())
                               : fmt::format("socketcan:{}", endpoint.device);
  std::unique_ptr<CanNode> node(new CanNode(std::move(ep.value()), governor, clock, name));
  CanNode* raw = node.get();
  governor.add_tick_listener([raw](const GovernorSnapshot& s) { raw->on_tick(s); });
  return node;
}

CanNode::CanNode(std::unique_ptr<drivers::can::CanEndpoint> ep, Governor& governor, ClockMode clock,
                 std::string endpoint)
    : ep_(std::move(ep)),
      governor_(governor),
      clock_(clock),
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

void CanNode::handle(const can_frame& frame) {
  const std::uint32_t pgn = j1939::pgn_of(frame);
  {
    std::lock_guard lock(mu_);
    ++counters_.received;
  }
  if (pgn == j1939::kPgnRigCommand) return handle_command(frame);
  if (pgn == j1939::kPgnTsc1) return handle_tsc1(frame);
  if (pgn == j1939::kPgnLockstep && clock_ == ClockMode::kLockstep) {
    auto m = j1939::decode_lockstep(frame);
    {
      std::lock_guard lock(mu_);
      ++(m ? counters_.accepted : counters_.bad_checksum);
    }
    if (m) governor_.advance(m->ticks);
    return;
  }
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
  governor_.set_enable(m->enable);
  governor_.heartbeat(CommandSource::kCan, m->counter);
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
  governor_.set_bias_pct(100.0 * (m->speed_rpm - synchronous_rpm_) / synchronous_rpm_);
  governor_.set_enable(true);
  governor_.heartbeat(CommandSource::kTsc1, m->counter);
}

void CanNode::on_tick(const GovernorSnapshot& s) {
  std::lock_guard lock(mu_);
  if (!ep_->has_peer() || s.link_dropped) return;
  const auto& m = s.measurement;
  can_frame sample = j1939::encode_plant_sample(
      j1939::PlantSample{m.power_w, s.counter(), static_cast<std::uint8_t>(s.status & 0xFF)});
  const bool power_na = s.power_invalid || !std::isfinite(m.power_w);
  if (power_na) mark_power_not_available(sample, true);
  send_locked(sample);
  const auto tick = governor_.tick_period();
  if (due(s, tick, kEec1Period)) {
    // Torque in % of rated: P = T w, so T/T_rated = (P/P_rated) (w_rated/w).
    const double torque_pct = m.speed_rpm > 0.0 ? 100.0 * m.power_w / governor_.rated_power_w() *
                                                      (synchronous_rpm_ / m.speed_rpm)
                                                : 0.0;
    send_locked(
        j1939::encode_eec1(j1939::Eec1{m.speed_rpm, std::clamp(torque_pct, -125.0, 125.0)}));
  }
  if (due(s, tick, kGtacpPeriod)) {
    can_frame gtacp = j1939::encode_gtacp(j1939::Gtacp{m.power_w, 0.0});
    if (power_na) mark_power_not_available(gtacp, false);
    send_locked(gtacp);
  }
}

void CanNode::send_locked(const can_frame& frame) {
  if (ep_->send(frame)) {
    ++counters_.sent;
  } else {
    ++counters_.send_failed;  // a full queue drops a sample, as a real bus would
  }
}

}  // namespace plantsim::serve
