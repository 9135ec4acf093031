#include "plantsim/serve/modbus_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>

#include "drivers/modbus/register_map.hpp"

namespace plantsim::serve {
namespace map = drivers::modbus_map;
namespace {

std::int64_t saturate(double value, std::int64_t lo, std::int64_t hi) {
  if (!std::isfinite(value)) return 0;
  return std::clamp<std::int64_t>(std::llround(std::clamp(value, -9e18, 9e18)), lo, hi);
}

}  // namespace

void encode_input_registers(const GovernorSnapshot& s, std::uint16_t* regs) {
  const auto& m = s.measurement;
  // INT32_MIN is reserved for "not available" (serve.nan_power, or a non-finite reading), so
  // a real reading saturates one above it and the rig maps INT32_MIN to NaN.
  const bool power_na = s.power_invalid || !std::isfinite(m.power_w);
  const auto power_w = static_cast<std::uint32_t>(
      power_na ? map::kPowerNotAvailable
               : static_cast<std::int32_t>(saturate(m.power_w, INT32_MIN + 1, INT32_MAX)));
  regs[map::kInPowerHi] = static_cast<std::uint16_t>(power_w >> 16);
  regs[map::kInPowerLo] = static_cast<std::uint16_t>(power_w & 0xFFFFu);
  regs[map::kInSpeed] =
      static_cast<std::uint16_t>(saturate(m.speed_rpm / map::kSpeedRpmPerBit, 0, 65535));
  regs[map::kInFreq] =
      static_cast<std::uint16_t>(saturate(m.freq_hz / map::kFreqHzPerBit, 0, 65535));
  regs[map::kInVoltage] =
      static_cast<std::uint16_t>(saturate(m.voltage_v / map::kVoltsPerBit, 0, 65535));
  regs[map::kInBiasEcho] = static_cast<std::uint16_t>(static_cast<std::int16_t>(
      saturate(s.bias_applied_pct / map::kBiasPctPerBit, INT16_MIN, INT16_MAX)));
  regs[map::kInStatus] = s.status;
  const auto time_ms = static_cast<std::uint32_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(s.plant_time).count());
  regs[map::kInTimeHi] = static_cast<std::uint16_t>(time_ms >> 16);
  regs[map::kInTimeLo] = static_cast<std::uint16_t>(time_ms & 0xFFFFu);
  regs[map::kInCounter] = s.counter();
}

drivers::LinkResult<std::unique_ptr<ModbusNode>> ModbusNode::open(const drivers::LinkUri& endpoint,
                                                                  Governor& governor,
                                                                  ClockMode clock) {
  drivers::ModbusServerOptions options;
  options.holding_count = map::kHoldingCount;
  options.input_count = map::kInputCount;
  options.unit = endpoint.unit;
  // PLANTSIM_MODBUS_DEBUG=1 prints libmodbus's frame trace (stdout) for debugging a rig.
  const char* debug = std::getenv("PLANTSIM_MODBUS_DEBUG");
  options.debug = debug != nullptr && std::string(debug) == "1";
  auto server =
      endpoint.scheme == drivers::LinkScheme::kModbusRtu
          ? drivers::ModbusServer::open_rtu(endpoint.device, endpoint.baud, endpoint.parity,
                                            endpoint.data_bits, endpoint.stop_bits, options)
          : drivers::ModbusServer::listen_tcp(endpoint.host, endpoint.port, options);
  if (!server) return server.error();
  std::unique_ptr<ModbusNode> node(new ModbusNode(std::move(server.value()), governor, clock));
  encode_input_registers(governor.snapshot(), node->server_->mapping().tab_input_registers);
  return node;
}

ModbusNode::ModbusNode(std::unique_ptr<drivers::ModbusServer> server, Governor& governor,
                       ClockMode clock)
    : server_(std::move(server)),
      endpoint_(server_->endpoint()),
      governor_(governor),
      clock_(clock) {}

ModbusNode::~ModbusNode() { stop(); }

void ModbusNode::start() {
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void ModbusNode::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

std::optional<drivers::LinkError> ModbusNode::failure() const {
  std::lock_guard lock(mu_);
  return failure_;
}

drivers::ModbusServerCounters ModbusNode::counters() const {
  std::lock_guard lock(mu_);
  return counters_;
}

void ModbusNode::run() {
  const auto hook = [this](const drivers::ModbusRequest& r, modbus_mapping_t& m) {
    on_request(r, m);
  };
  // The poll timeout only bounds how long stop() waits; traffic wakes the loop at once.
  while (!stop_) {
    auto result = server_->poll(std::chrono::milliseconds(50), hook);
    std::lock_guard lock(mu_);
    counters_ = server_->counters();
    if (!result) {
      failure_ = result.error();
      return;
    }
    if (governor_.snapshot().link_dropped) break;
  }
  if (stop_) return;
  // serve.drop_link: closing the listener and every connection is what the rig sees when a
  // gateway or cable goes (ECONNRESET, then ECONNREFUSED); nothing answers any more.
  {
    std::lock_guard lock(mu_);
    server_.reset();
  }
  while (!stop_) std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

void ModbusNode::on_request(const drivers::ModbusRequest& request, modbus_mapping_t& m) {
  if (request.is_write() && request.write_in_range) {
    std::uint32_t advance_ticks = 0;
    for (std::size_t i = 0; i < request.values.size(); ++i) {
      const int address = request.write_address + static_cast<int>(i);
      const std::uint16_t v = request.values[i];
      if (address == map::kHoldBias) {
        governor_.set_bias_pct(static_cast<std::int16_t>(v) * map::kBiasPctPerBit);
      } else if (address == map::kHoldHeartbeat) {
        governor_.heartbeat(CommandSource::kModbus, v);
      } else if (address == map::kHoldControl) {
        governor_.set_enable((v & map::kControlEnableBias) != 0);
      } else if (address == map::kHoldLockstepTicks && clock_ == ClockMode::kLockstep) {
        advance_ticks = v;
      }
    }
    // After the other registers of the same request, so a block write's bias counts.
    if (advance_ticks > 0) governor_.advance(advance_ticks);
  }
  encode_input_registers(governor_.snapshot(), m.tab_input_registers);
}

}  // namespace plantsim::serve
