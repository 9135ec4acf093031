#include "drivers/can/can_link.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"

namespace drivers {
namespace {

namespace j = j1939;
using Clock = std::chrono::steady_clock;
constexpr int kMaxFramesPerRead = 4096;

bool power_bytes_not_available(const can_frame& f) {
  return f.can_dlc == 8 && f.data[0] == 0xFF && f.data[1] == 0xFF && f.data[2] == 0xFF &&
         f.data[3] == 0xFF;
}

// PGN 0xFF51 whose power reads J1939 "not available" (0xFFFFFFFF) but whose checksum and
// counter are right: a valid sample with NaN power, so the supervisor trips on it as a
// non-finite reading rather than as a broken link.
std::optional<j::PlantSample> plant_sample_without_power(const can_frame& f) {
  if (!power_bytes_not_available(f)) return std::nullopt;
  const std::uint8_t nibble = f.data[7] >> 4;
  const std::uint16_t counter = static_cast<std::uint16_t>(f.data[4] | (f.data[5] << 8));
  if ((f.data[7] & 0x0F) != j::checksum4(f.data, nibble, f.can_id & CAN_EFF_MASK) ||
      nibble != (counter & 0x0F)) {
    return std::nullopt;
  }
  return j::PlantSample{std::numeric_limits<double>::quiet_NaN(), counter, f.data[6]};
}

}  // namespace

CanLink::CanLink(LinkUri uri, const LinkOptions& options)
    : LinkBase(options), uri_(std::move(uri)), counter_(options_) {}

CanLink::~CanLink() = default;

void CanLink::close() { endpoint_.reset(); }

LinkResult<void> CanLink::configure() {
  close();
  counter_.reset();
  last_seen_.reset();
  // enabled_ and last_bias_pct_ survive a reconnect: deactivate() after configure() ramps the
  // bias the governor may still hold with the enable set, then clears it.
  command_since_read_ = false;
  awaiting_echo_ = false;
  warnings_.clear();
  if (uri_.can_command == CanCommand::kTsc1) {
    warnings_.push_back(fmt::format(
        "{}: TSC1 speed requests have a resolution of 0.125 rpm = {:.4f} % of bias at {:g} rpm "
        "(0xFF50: 0.001 %); small excitations are coarsely quantised",
        uri_.text, 100.0 * j::kSpeedRpmPerBit / uri_.sync_rpm, uri_.sync_rpm));
  }
  auto ep = can::open_can_endpoint(uri_, can::CanRole::kClient);
  if (!ep) return ep.error();
  endpoint_ = std::move(ep.value());
  return {};
}

// 0xFF50 carries the bias and the enable state. TSC1 carries a speed request
// n = sync_rpm (1 + bias / 100) in override mode "speed control", and "no override" (mode 00)
// to disable. Every command is answered by a 0xFF53 echo carrying its counter.
LinkResult<void> CanLink::send_command(double bias_pct, bool enable, const char* call) {
  if (!endpoint_) return not_configured(call);
  tx_counter_ = static_cast<std::uint8_t>((tx_counter_ + 1) & 0x0F);
  const bool tsc1 = uri_.can_command == CanCommand::kTsc1;
  const double applied_pct = j::quantise_bias_slot(bias_pct);
  last_sent_pct_ = applied_pct;
  const can_frame f =
      tsc1 ? j::encode_tsc1({uri_.sync_rpm * (1.0 + applied_pct / 100.0), tx_counter_, !enable})
           : j::encode_rig_command({bias_pct, enable, tx_counter_});
  auto r = endpoint_->send(f);
  if (!r) {
    return LinkError{r.error().kind,
                     std::string(tsc1 ? "PGN 0x0000 (TSC1)" : "PGN 0xFF50") + " on " + uri_.text,
                     r.error().detail};
  }
  enabled_ = enable;
  command_since_read_ = true;
  awaiting_echo_ = true;
  last_bias_pct_ = applied_pct;
  return {};
}

LinkResult<void> CanLink::send_idle_if_due(const char* call) {
  if (enabled_ || command_since_read_) return {};
  return send_command(0.0, false, call);
}

LinkResult<void> CanLink::write(double bias_pct) {
  return send_command(bias_pct, enabled_, "write");
}

LinkResult<void> CanLink::advance(std::uint16_t ticks) {
  if (ticks == 0) return {};
  if (!endpoint_) return not_configured("advance");
  // Before 0xFF52, so that the idle frame takes effect (and is echoed) within these ticks.
  if (auto r = send_idle_if_due("advance"); !r) return r;
  auto r = endpoint_->send(j::encode_lockstep({ticks}));
  if (!r) return LinkError{r.error().kind, "PGN 0xFF52 on " + uri_.text, r.error().detail};
  counter_.expect_ticks(ticks);
  return {};
}

LinkResult<void> CanLink::apply_sample(const can_frame& f, ReadState& st) {
  auto m = j::decode_plant_sample(f);
  if (!m) {
    auto na = plant_sample_without_power(f);
    if (!na) return m.error();
    m = *na;
  }
  if (last_seen_ && m->counter == *last_seen_) {
    st.saw_old = true;  // the tick we already returned
    return {};
  }
  unwrapped_ =
      last_seen_ ? unwrapped_ + static_cast<std::uint16_t>(m->counter - *last_seen_) : m->counter;
  last_seen_ = m->counter;
  sample_.power_kw = m->power_w / 1000.0;
  sample_.status = m->status;
  sample_.counter = m->counter;
  if (!target_ || m->counter == *target_) st.fresh = true;
  return {};
}

// A malformed echo is ignored: the read then reports the echo missing.
LinkResult<double> CanLink::read_held_bias() {
  if (!echo_seen_) {
    return LinkError{LinkErrorKind::kUnavailable, "PGN 0xFF53", "no bias echo received yet"};
  }
  return sample_.bias_echo_pct;
}

void CanLink::apply_echo(const can_frame& f) {
  auto m = j::decode_bias_echo(f);
  if (!m) return;
  sample_.bias_echo_pct = m->applied_pct;
  sample_.status = m->status;
  echo_seen_ = true;
  if (m->command_counter == tx_counter_) awaiting_echo_ = false;
}

LinkResult<void> CanLink::apply(const can_frame& f, ReadState& st) {
  if (j::source_of(f) != j::kGovernorAddress) return {};
  switch (j::pgn_of(f)) {
    case j::kPgnPlantSample:
      return apply_sample(f, st);
    case j::kPgnBiasEcho:
      apply_echo(f);
      return {};
    case j::kPgnEec1: {
      auto m = j::decode_eec1(f);
      if (m) sample_.speed_rpm = m->speed_rpm;  // "not available" keeps the last value
      return {};
    }
    case j::kPgnGtacp: {
      auto m = j::decode_gtacp(f);
      if (!m && power_bytes_not_available(f)) {
        sample_.power_kw = std::numeric_limits<double>::quiet_NaN();
        return {};
      }
      if (!m) return m.error();
      sample_.power_kw = m->real_power_w / 1000.0;
      return {};
    }
    default:
      return {};
  }
}

LinkResult<Sample> CanLink::read() {
  if (!endpoint_) return not_configured("read");
  if (auto r = send_idle_if_due("read"); !r) return r.error();
  command_since_read_ = false;
  const auto deadline = Clock::now() + options_.response_timeout;
  target_.reset();
  if (counter_.pending_ticks() != 0 && counter_.last()) {
    target_ = static_cast<std::uint16_t>(*counter_.last() + counter_.pending_ticks());
  }
  ReadState st;
  // Bounded so that a flooding sender cannot hold read() past its deadline.
  for (int frames = 0; frames < kMaxFramesPerRead; ++frames) {
    // Once the awaited tick and echo are in, only drain what is already queued.
    const bool done = st.fresh && !awaiting_echo_;
    const auto left = done ? std::chrono::milliseconds(0)
                           : std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    auto f = endpoint_->receive(std::max(left, std::chrono::milliseconds(0)));
    if (!f) {
      if (f.error().kind != LinkErrorKind::kTimeout) return f.error();
      break;
    }
    if (auto r = apply(*f, st); !r) return r.error();
    if (!done && Clock::now() >= deadline) break;
  }
  if (!st.fresh || awaiting_echo_) return missing(st);
  return finish(Clock::now());
}

LinkResult<Sample> CanLink::missing(const ReadState& st) const {
  const std::string within = " within " + std::to_string(options_.response_timeout.count()) + " ms";
  if (st.fresh) {
    return LinkError{LinkErrorKind::kTimeout, "PGN 0xFF53 on " + uri_.text,
                     "no bias echo for command counter " + std::to_string(tx_counter_) + within};
  }
  const std::string where = "PGN 0xFF51 on " + uri_.text;
  if (st.saw_old || (target_ && counter_.last() && sample_.counter != *counter_.last())) {
    return LinkError{
        LinkErrorKind::kStale, where,
        "no new plant tick" + within + " (counter " + std::to_string(sample_.counter) + ")"};
  }
  return LinkError{LinkErrorKind::kTimeout, where, "no frame" + within};
}

LinkResult<Sample> CanLink::finish(Clock::time_point now) {
  if (auto r = counter_.check(sample_.counter, now, "PGN 0xFF51 on " + uri_.text); !r) {
    return r.error();
  }
  const double tick_s = std::chrono::duration<double>(options_.plant_tick).count();
  sample_.plant_time_s = static_cast<double>(unwrapped_) * tick_s;
  return sample_;
}

std::unique_ptr<GovernorLink> make_can_link(const LinkUri& uri, const LinkOptions& options) {
  return std::make_unique<CanLink>(uri, options);
}

std::vector<std::string> link_warnings(const GovernorLink& link) {
  const auto* can = dynamic_cast<const CanLink*>(&link);
  return can != nullptr ? can->warnings() : std::vector<std::string>{};
}

}  // namespace drivers
