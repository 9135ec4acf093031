// A Modbus server (slave) built on libmodbus: TCP with several clients on one select() loop,
// or RTU on a serial device. The register map is one modbus_mapping_t (holding and input
// registers, sized from drivers/modbus/register_map.hpp by the caller); libmodbus's
// modbus_reply() answers reads, writes and the exceptions illegal data address 02 and illegal
// data value 03. Only the function codes in ModbusServerOptions::functions are served (the
// documented map: 03, 04, 06, 16); every other code is answered here with exception 01
// (illegal function) and acts on nothing. libmodbus alone would serve 0x16/0x17 (writing
// holding registers past the map's rules) and leave 07 unanswered (the client times out).
// RTU broadcasts (unit 0) are never answered, as Modbus requires.
//
// TCP framing is done here on non-blocking per-connection buffers (the MBAP length field says
// how long the ADU is) instead of modbus_receive(), whose byte timeout would let one slow or
// misbehaving client stall every other client. A connection that sends bytes that are not
// Modbus TCP (protocol id != 0, length outside 2..254) cannot be answered with an exception,
// so it is closed; the listener and the other connections carry on.
//
// The caller sees every well-formed request before it is answered (`before_reply`), so it can
// act on writes (e.g. advance a simulated plant) and refresh the input registers first.
#pragma once

#include <modbus/modbus.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/governor_link.hpp"

namespace drivers {

// A decoded request. For writes (function 06, 16) `values` holds the registers written
// starting at `write_address`; `write_in_range` says whether that span fits the map (if not,
// libmodbus answers exception 02 and nothing is written).
struct ModbusRequest {
  int unit = 0;
  int function = 0;
  int address = 0;
  int write_address = 0;
  std::vector<std::uint16_t> values;
  bool write_in_range = false;
  bool is_write() const { return !values.empty(); }
};

struct ModbusServerCounters {
  std::uint64_t requests = 0;   // well-formed requests answered (incl. exceptions)
  std::uint64_t malformed = 0;  // frames that could not be parsed (connection closed / RTU flushed)
  std::uint64_t connections = 0;  // TCP connections accepted
  std::uint64_t refused = 0;      // TCP connections closed at once (too many clients)
};

struct ModbusServerOptions {
  int holding_count = 0;
  int input_count = 0;
  int unit = 1;          // RTU: requests for other units are ignored; TCP: any unit answered
  int max_clients = 16;  // TCP
  bool debug = false;    // libmodbus frame trace on stderr
  // Function codes served; any other is answered with exception 01 (illegal function).
  std::vector<std::uint8_t> functions = {
      MODBUS_FC_READ_HOLDING_REGISTERS, MODBUS_FC_READ_INPUT_REGISTERS,
      MODBUS_FC_WRITE_SINGLE_REGISTER, MODBUS_FC_WRITE_MULTIPLE_REGISTERS};
  bool serves(int function) const;
};

class ModbusServer {
 public:
  using Hook = std::function<void(const ModbusRequest&, modbus_mapping_t&)>;

  // Binds host:port (port 0 = ephemeral) and listens. Errors name the endpoint and the OS text.
  static LinkResult<std::unique_ptr<ModbusServer>> listen_tcp(const std::string& host, int port,
                                                              const ModbusServerOptions& options);
  // Opens a serial device as an RTU slave (parity 'N', 'E' or 'O').
  static LinkResult<std::unique_ptr<ModbusServer>> open_rtu(const std::string& device, int baud,
                                                            char parity, int data_bits,
                                                            int stop_bits,
                                                            const ModbusServerOptions& options);
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  // Waits at most `timeout` for traffic and answers every complete request, calling
  // `before_reply` first. Returns an error only when the transport itself failed (e.g. the
  // serial device vanished); per-client trouble is handled inside.
  LinkResult<void> poll(std::chrono::milliseconds timeout, const Hook& before_reply);

  modbus_mapping_t& mapping() { return *mapping_; }
  int port() const { return port_; }  // actual TCP port (after an ephemeral bind)
  std::string endpoint() const;       // "tcp://127.0.0.1:40123" or "rtu:/dev/ttyX?baud=19200"
  const ModbusServerCounters& counters() const { return counters_; }
  int client_count() const { return static_cast<int>(clients_.size()); }

 private:
  struct Client {
    int fd = -1;
    std::vector<std::uint8_t> buffer;
  };
  ModbusServer(modbus_t* ctx, modbus_mapping_t* mapping, ModbusServerOptions options);

  LinkResult<void> poll_tcp(std::chrono::milliseconds timeout, const Hook& before_reply);
  LinkResult<void> poll_rtu(std::chrono::milliseconds timeout, const Hook& before_reply);
  void accept_client();
  // Reads what is available and answers complete ADUs; false when the client must be closed.
  bool serve_client(Client& client, const Hook& before_reply);
  void answer(const std::uint8_t* adu, int length, const Hook& before_reply);
  void close_client(std::size_t index);

  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  ModbusServerOptions options_;
  bool rtu_ = false;
  int listen_fd_ = -1;
  int port_ = 0;
  std::string host_;
  std::string device_;
  int baud_ = 0;
  std::vector<Client> clients_;
  ModbusServerCounters counters_;
};

// Decodes a request ADU (TCP: MBAP header of 7 bytes; RTU: 1 byte unit) into ModbusRequest.
// `buffer` must hold at least MODBUS_MAX_ADU_LENGTH bytes (zero past `length`), as libmodbus
// itself reads fixed offsets. Pure; exposed for tests.
ModbusRequest decode_request(const std::uint8_t* buffer, int length, int header_length,
                             int holding_count);

}  // namespace drivers
