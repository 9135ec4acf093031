#include "drivers/can/can_link.hpp"

#include <algorithm>
#include <limits>
#include <optional>

#include "drivers/bias.hpp"
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

class CanLink final : public LinkBase {
 public:
  CanLink(LinkUri uri, const LinkOptions& options)
      : LinkBase(options), uri_(std::move(uri)), counter_(options_) {}

  LinkResult<void> configure() override;
  LinkResult<void> activate() override { return send_command(0.0, true, "activate"); }
  LinkResult<void> write(double bias_pct) override;
  LinkResult<Sample> read() override;
  LinkResult<void> advance(std::uint16_t ticks) override;
  void close() override { endpoint_.reset(); }
  std::string uri() const override { return uri_.text; }

 protected:
  LinkResult<void> disable() override { return send_command(0.0, false, "deactivate"); }

 private:
  LinkResult<void> send_command(double bias_pct, bool enable, const char* call);
  // Applies one received frame to sample_; sets `fresh` when it is the awaited 0xFF51.
  LinkResult<void> apply(const can_frame& f, bool& fresh, bool& saw_old);
  LinkResult<Sample> finish(Clock::time_point now);

  LinkUri uri_;
  std::unique_ptr<can::CanEndpoint> endpoint_;
  CounterCheck counter_;
  bool enabled_ = false;
  std::uint8_t tx_counter_ = 0;
  Sample sample_;
  std::optional<std::uint16_t> target_;  // counter awaited by this read (lockstep)
  // Lockstep, first read: the counter is not known yet, so the first 0xFF51 that arrives opens
  // the burst of `burst_ticks_` new ticks and the awaited one is the burst's last.
  std::uint32_t burst_ticks_ = 0;
  std::uint64_t unwrapped_ = 0;          // sample counter without 16-bit wrap
  std::optional<std::uint16_t> last_seen_;
};

LinkResult<void> CanLink::configure() {
  close();
  counter_.reset();
  last_seen_.reset();
  auto ep = can::open_can_endpoint(uri_, can::CanRole::kClient);
  if (!ep) return ep.error();
  endpoint_ = std::move(ep.value());
  return {};
}

// 0xFF50 carries the bias and the enable bit. TSC1 carries only a speed request
// n = sync_rpm (1 + bias / 100); it has no enable bit, so disabling sends the synchronous speed
// (zero bias) and the governor's TSC1 timeout releases the override when the frames stop.
LinkResult<void> CanLink::send_command(double bias_pct, bool enable, const char* call) {
  if (!endpoint_) return not_configured(call);
  tx_counter_ = static_cast<std::uint8_t>((tx_counter_ + 1) & 0x0F);
  const bool tsc1 = uri_.can_command == CanCommand::kTsc1;
  const double applied_pct = bias_from_raw(quantise_bias(bias_pct));
  const can_frame f =
      tsc1 ? j::encode_tsc1(
                 {uri_.sync_rpm * (1.0 + (enable ? applied_pct : 0.0) / 100.0), tx_counter_})
           : j::encode_rig_command({bias_pct, enable, tx_counter_});
  auto r = endpoint_->send(f);
  if (!r) {
    return LinkError{r.error().kind,
                     std::string(tsc1 ? "PGN 0x0000 (TSC1)" : "PGN 0xFF50") + " on " + uri_.text,
                     r.error().detail};
  }
  enabled_ = enable;
  last_bias_pct_ = applied_pct;
  return {};
}

LinkResult<void> CanLink::write(double bias_pct) {
  return send_command(bias_pct, enabled_, "write");
}

LinkResult<void> CanLink::advance(std::uint16_t ticks) {
  if (ticks == 0) return {};
  if (!endpoint_) return not_configured("advance");
  auto r = endpoint_->send(j::encode_lockstep({ticks}));
  if (!r) return LinkError{r.error().kind, "PGN 0xFF52 on " + uri_.text, r.error().detail};
  counter_.expect_ticks(ticks);
  return {};
}

LinkResult<void> CanLink::apply(const can_frame& f, bool& fresh, bool& saw_old) {
  if (j::source_of(f) != j::kGovernorAddress) return {};
  switch (j::pgn_of(f)) {
    case j::kPgnPlantSample: {
      auto m = j::decode_plant_sample(f);
      if (!m) {
        auto na = plant_sample_without_power(f);
        if (!na) return m.error();
        m = *na;
      }
      if (last_seen_ && m->counter == *last_seen_) {
        saw_old = true;  // the tick we already returned
        return {};
      }
      unwrapped_ = last_seen_ ? unwrapped_ + static_cast<std::uint16_t>(m->counter - *last_seen_)
                              : m->counter;
      last_seen_ = m->counter;
      if (!target_ && burst_ticks_ > 0) {
        target_ = static_cast<std::uint16_t>(m->counter + burst_ticks_ - 1);
        burst_ticks_ = 0;
      }
      sample_.power_kw = m->power_w / 1000.0;
      sample_.status = m->status;
      sample_.counter = m->counter;
      if (!target_ || m->counter == *target_) fresh = true;
      return {};
    }
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
  const std::string where = "PGN 0xFF51 on " + uri_.text;
  const auto deadline = Clock::now() + options_.response_timeout;
  target_.reset();
  burst_ticks_ = 0;
  if (counter_.pending_ticks() != 0) {
    if (counter_.last()) {
      target_ = static_cast<std::uint16_t>(*counter_.last() + counter_.pending_ticks());
    } else {
      burst_ticks_ = counter_.pending_ticks();
    }
  }
  bool fresh = false;
  bool saw_old = false;
  // Bounded so that a flooding sender cannot hold read() past its deadline.
  for (int frames = 0; frames < kMaxFramesPerRead; ++frames) {
    // Once the awaited tick is in, only drain what is already queued.
    const auto left = fresh ? std::chrono::milliseconds(0)
                            : std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    auto f = endpoint_->receive(std::max(left, std::chrono::milliseconds(0)));
    if (!f) {
      if (f.error().kind != LinkErrorKind::kTimeout) return f.error();
      break;
    }
    if (auto r = apply(*f, fresh, saw_old); !r) return r.error();
    if (!fresh && Clock::now() >= deadline) break;
  }
  if (!fresh) {
    if (saw_old || (target_ && sample_.counter != *counter_.last())) {
      return LinkError{LinkErrorKind::kStale, where,
                       "no new plant tick within " +
                           std::to_string(options_.response_timeout.count()) + " ms (counter " +
                           std::to_string(sample_.counter) + ")"};
    }
    return LinkError{
        LinkErrorKind::kTimeout, where,
        "no frame within " + std::to_string(options_.response_timeout.count()) + " ms"};
  }
  return finish(Clock::now());
}

LinkResult<Sample> CanLink::finish(Clock::time_point now) {
  if (auto r = counter_.check(sample_.counter, now, "PGN 0xFF51 on " + uri_.text); !r) {
    return r.error();
  }
  const double tick_s = std::chrono::duration<double>(options_.plant_tick).count();
  sample_.plant_time_s = static_cast<double>(unwrapped_) * tick_s;
  return sample_;
}

}  // namespace

std::unique_ptr<GovernorLink> make_can_link(const LinkUri& uri, const LinkOptions& options) {
  return std::make_unique<CanLink>(uri, options);
}

}  // namespace drivers
