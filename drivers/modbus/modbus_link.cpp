#include "drivers/modbus/modbus_link.hpp"

#include <modbus.h>

#include <cerrno>
#include <cstring>
#include <limits>

#include "drivers/bias.hpp"
#include "drivers/modbus/register_map.hpp"

namespace drivers {

LinkError modbus_error(int err, const std::string& where) {
  std::string text = modbus_strerror(err);
  if (err >= EMBXILFUN && err <= EMBXGTAR) {
    return LinkError{LinkErrorKind::kModbusException, where,
                     text + " (exception " + std::to_string(err - MODBUS_ENOBASE) + ")"};
  }
  switch (err) {
    case ETIMEDOUT:
      return LinkError{LinkErrorKind::kTimeout, where, text};
    case EMBBADCRC:
      return LinkError{LinkErrorKind::kChecksum, where, text};
    case EMBBADDATA:
    case EMBBADEXC:
    case EMBUNKEXC:
    case EMBMDATA:
    case EMBBADSLAVE:
      return LinkError{LinkErrorKind::kProtocol, where, text};
    default:  // ECONNRESET, EPIPE, ECONNREFUSED, EBADF, EIO, ENOENT, ...
      return LinkError{LinkErrorKind::kLinkLost, where, text};
  }
}

namespace {

namespace map = modbus_map;

struct ContextFree {
  void operator()(modbus_t* ctx) const {
    modbus_close(ctx);
    modbus_free(ctx);
  }
};

class ModbusLink final : public LinkBase {
 public:
  ModbusLink(LinkUri uri, const LinkOptions& options)
      : LinkBase(options), uri_(std::move(uri)), counter_(options_) {}
  ~ModbusLink() override { close(); }

  LinkResult<void> configure() override;
  LinkResult<void> activate() override { return write_control(0.0, true, "activate"); }
  LinkResult<void> write(double bias_pct) override;
  LinkResult<Sample> read() override;
  LinkResult<void> advance(std::uint16_t ticks) override;
  LinkResult<double> read_held_bias() override;
  void close() override { ctx_.reset(); }
  std::string uri() const override { return uri_.text; }

 protected:
  LinkResult<void> disable() override { return write_control(0.0, false, "deactivate"); }

 private:
  LinkResult<void> write_control(double bias_pct, bool enable, const char* call);
  LinkResult<void> write_holding(int first, int count, const std::uint16_t* values);

  LinkUri uri_;
  std::unique_ptr<modbus_t, ContextFree> ctx_;
  std::uint16_t heartbeat_ = 0;
  CounterCheck counter_;
};

LinkResult<void> ModbusLink::configure() {
  close();
  counter_.reset();
  modbus_t* raw = uri_.scheme == LinkScheme::kModbusTcp
                      ? modbus_new_tcp(uri_.host.c_str(), uri_.port)
                      : modbus_new_rtu(uri_.device.c_str(), uri_.baud, uri_.parity, uri_.data_bits,
                                       uri_.stop_bits);
  if (!raw) return LinkError{LinkErrorKind::kConfig, uri_.text, modbus_strerror(errno)};
  std::unique_ptr<modbus_t, ContextFree> ctx(raw);
  const auto us =
      std::chrono::duration_cast<std::chrono::microseconds>(options_.response_timeout).count();
  if (modbus_set_slave(raw, uri_.unit) != 0 ||
      modbus_set_response_timeout(raw, static_cast<std::uint32_t>(us / 1000000),
                                  static_cast<std::uint32_t>(us % 1000000)) != 0) {
    return LinkError{LinkErrorKind::kConfig, uri_.text, modbus_strerror(errno)};
  }
  if (modbus_connect(raw) != 0) return modbus_error(errno, uri_.text + " connect");
  ctx_ = std::move(ctx);
  return {};
}

LinkResult<void> ModbusLink::write_holding(int first, int count, const std::uint16_t* values) {
  const std::string where =
      count == 1 ? "holding " + std::to_string(first)
                 : "holding " + std::to_string(first) + "-" + std::to_string(first + count - 1);
  if (!ctx_) return not_configured(where + " write");
  const int n = count == 1 ? modbus_write_register(ctx_.get(), first, values[0])
                           : modbus_write_registers(ctx_.get(), first, count, values);
  if (n < 0) {
    const int err = errno;
    if (err == ETIMEDOUT) modbus_flush(ctx_.get());  // drop a late answer
    return modbus_error(err, where);
  }
  return {};
}

LinkResult<void> ModbusLink::write(double bias_pct) {
  const std::int16_t raw = quantise_bias(bias_pct);
  const std::uint16_t regs[2] = {static_cast<std::uint16_t>(raw), ++heartbeat_};
  last_sent_pct_ = bias_from_raw(raw);
  auto r = write_holding(map::kHoldBias, 2, regs);
  if (r) last_bias_pct_ = bias_from_raw(raw);
  return r;
}

LinkResult<void> ModbusLink::write_control(double bias_pct, bool enable, const char* call) {
  if (!ctx_) return not_configured(call);
  const std::int16_t raw = quantise_bias(bias_pct);
  const std::uint16_t regs[3] = {static_cast<std::uint16_t>(raw), ++heartbeat_,
                                 enable ? map::kControlEnableBias : std::uint16_t{0}};
  last_sent_pct_ = bias_from_raw(raw);
  auto r = write_holding(map::kHoldBias, 3, regs);
  if (r) last_bias_pct_ = bias_from_raw(raw);
  return r;
}

LinkResult<void> ModbusLink::advance(std::uint16_t ticks) {
  if (ticks == 0) return {};
  const std::uint16_t value = ticks;
  auto r = write_holding(map::kHoldLockstepTicks, 1, &value);
  if (r) counter_.expect_ticks(ticks);
  return r;
}

// What the governor applies now: the echo, input 5 (after a heartbeat loss the governor has
// dropped the bias though holding 0 may still hold it; the ramp must not re-apply that).
LinkResult<double> ModbusLink::read_held_bias() {
  const std::string where = "input " + std::to_string(map::kInBiasEcho);
  if (!ctx_) return not_configured(where + " read");
  std::uint16_t echo = 0;
  if (modbus_read_input_registers(ctx_.get(), map::kInBiasEcho, 1, &echo) != 1) {
    const int err = errno;
    if (err == ETIMEDOUT) modbus_flush(ctx_.get());
    return modbus_error(err, where);
  }
  return bias_from_raw(static_cast<std::int16_t>(echo));
}

LinkResult<Sample> ModbusLink::read() {
  const std::string where = "input 0-" + std::to_string(map::kInputCount - 1);
  if (!ctx_) return not_configured(where + " read");
  std::uint16_t in[map::kInputCount] = {};
  const int n = modbus_read_input_registers(ctx_.get(), 0, map::kInputCount, in);
  if (n < 0) {
    const int err = errno;
    if (err == ETIMEDOUT) modbus_flush(ctx_.get());
    return modbus_error(err, where);
  }
  if (n != map::kInputCount) {
    return LinkError{
        LinkErrorKind::kProtocol, where,
        "got " + std::to_string(n) + " registers, expected " + std::to_string(map::kInputCount)};
  }
  auto word32 = [&](int hi) {
    return (std::uint32_t{in[hi]} << 16) | std::uint32_t{in[hi + 1]};  // high word first
  };
  Sample s;
  // INT32_MIN is the governor's "not available": NaN, which the supervisor trips on.
  const auto power_w = static_cast<std::int32_t>(word32(map::kInPowerHi));
  s.power_kw = power_w == map::kPowerNotAvailable ? std::numeric_limits<double>::quiet_NaN()
                                                  : power_w / 1000.0;
  s.speed_rpm = in[map::kInSpeed] * map::kSpeedRpmPerBit;
  s.freq_hz = in[map::kInFreq] * map::kFreqHzPerBit;
  s.voltage_v = in[map::kInVoltage] * map::kVoltsPerBit;
  s.bias_echo_pct = bias_from_raw(static_cast<std::int16_t>(in[map::kInBiasEcho]));
  s.status = in[map::kInStatus];
  s.plant_time_s = word32(map::kInTimeHi) / 1000.0;
  s.counter = in[map::kInCounter];
  if (auto r = counter_.check(s.counter, CounterCheck::Clock::now(),
                              "input " + std::to_string(map::kInCounter));
      !r) {
    return r.error();
  }
  return s;
}

}  // namespace

std::unique_ptr<GovernorLink> make_modbus_link(const LinkUri& uri, const LinkOptions& options) {
  return std::make_unique<ModbusLink>(uri, options);
}

}  // namespace drivers
