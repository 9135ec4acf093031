#include "tests/unit/live/mqtt_broker.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace rig::live::testing {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// A broker starts in tens of milliseconds; a loaded 2-core machine may take a few seconds.
constexpr milliseconds kBrokerStartTimeout{5000};
// mosquitto_sub ends by itself after this long, in case a test forgets it.
constexpr const char* kSubscriberLifetimeS = "60";

sockaddr_in loopback(int port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return addr;
}

bool accepts(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  const sockaddr_in addr = loopback(port);
  const bool ok = connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  return ok;
}

std::string required_program(const std::string& name) {
  std::string path = find_program(name);
  if (path.empty()) {
    throw std::runtime_error(name + " not found (scripts/setup installs mosquitto and " +
                             "mosquitto-clients)");
  }
  return path;
}

}  // namespace

std::string find_program(const std::string& name) {
  const char* env = std::getenv("PATH");
  std::string dirs = std::string(env ? env : "") + ":/usr/sbin:/usr/bin:/usr/local/sbin";
  std::stringstream in(dirs);
  for (std::string dir; std::getline(in, dir, ':');) {
    if (dir.empty()) continue;
    const std::filesystem::path p = std::filesystem::path(dir) / name;
    if (access(p.c_str(), X_OK) == 0) return p.string();
  }
  return {};
}

int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error("cannot open a socket");
  sockaddr_in addr = loopback(0);
  socklen_t len = sizeof addr;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    close(fd);
    throw std::runtime_error("cannot find a free port");
  }
  close(fd);
  return ntohs(addr.sin_port);
}

// mosquitto 2 listens on localhost only and refuses anonymous clients unless a config file
// says otherwise; the log goes to a file so that a full stderr pipe cannot stall the broker.
Broker::Broker(int port) : port_(port) {
  dir_ = std::filesystem::temp_directory_path() /
         ("rig_mqtt_" + std::to_string(getpid()) + "_" + std::to_string(port));
  std::filesystem::create_directories(dir_);
  std::ofstream(dir_ / "mosquitto.conf")
      << "listener " << port << " 127.0.0.1\n"
      << "allow_anonymous true\n"
      << "log_dest file " << (dir_ / "broker.log").string() << "\n";
  start();
}

Broker::~Broker() {
  process_.reset();
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

void Broker::start() {
  process_ = std::make_unique<ChildProcess>(std::vector<std::string>{
      required_program("mosquitto"), "-c", (dir_ / "mosquitto.conf").string()});
  const auto deadline = Clock::now() + kBrokerStartTimeout;
  while (!accepts(port_)) {
    if (Clock::now() > deadline || process_->wait(milliseconds(0))) {
      throw std::runtime_error("mosquitto did not start on port " + std::to_string(port_));
    }
    std::this_thread::sleep_for(milliseconds(10));
  }
}

void Broker::kill() {
  process_->signal(SIGKILL);
  process_->wait(kBrokerStartTimeout);
}

void Broker::restart() {
  kill();
  start();
}

Subscriber::Subscriber(int port, const std::string& filter, int count) : port_(port) {
  std::vector<std::string> argv{required_program("mosquitto_sub"),
                                "-h",
                                "127.0.0.1",
                                "-p",
                                std::to_string(port),
                                "-q",
                                "1",
                                "-t",
                                filter,
                                "-F",
                                "%r %q %t %p",
                                "-W",
                                kSubscriberLifetimeS};
  if (count > 0) {
    argv.push_back("-C");
    argv.push_back(std::to_string(count));
  }
  process_ = std::make_unique<ChildProcess>(std::move(argv));
}

bool Subscriber::wait_ready(const std::string& probe_topic, milliseconds timeout) {
  probe_topic_ = probe_topic;
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    mqtt_pub(port_, probe_topic, "probe");
    const auto until = std::min(deadline, Clock::now() + milliseconds(200));
    while (Clock::now() < until) {
      const auto line = read(std::chrono::duration_cast<milliseconds>(until - Clock::now()));
      if (!line) break;
      if (line->topic == probe_topic) return true;
      lines_.push_back(*line);
    }
  }
  return false;
}

std::optional<MqttLine> Subscriber::read(milliseconds timeout) {
  const auto text = process_->read_line(timeout);
  if (!text) return std::nullopt;
  MqttLine line;
  std::istringstream in(*text);
  int retained = 0;
  in >> retained >> line.qos >> line.topic;
  line.retained = retained != 0;
  std::getline(in >> std::ws, line.payload);
  return line;
}

std::optional<MqttLine> Subscriber::next(milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
    auto line = read(std::max(left, milliseconds(0)));
    if (!line) return std::nullopt;
    if (!probe_topic_.empty() && line->topic == probe_topic_) continue;  // a late probe
    lines_.push_back(*line);
    return line;
  }
}

bool Subscriber::wait_for(const std::string& topic, const std::string& needle,
                          milliseconds timeout) {
  auto matches = [&](const MqttLine& l) {
    return l.topic == topic && l.payload.find(needle) != std::string::npos;
  };
  // Lines read but not yet looked at by a wait_for (e.g. while waiting to be ready) first.
  while (scanned_ < lines_.size()) {
    if (matches(lines_[scanned_++])) return true;
  }
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    const auto line = next(std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
    if (!line) return false;
    scanned_ = lines_.size();
    if (matches(*line)) return true;
  }
  return false;
}

bool mqtt_pub(int port, const std::string& topic, const std::string& payload) {
  ChildProcess pub({required_program("mosquitto_pub"), "-h", "127.0.0.1", "-p",
                    std::to_string(port), "-t", topic, "-m", payload});
  return pub.wait(kBrokerStartTimeout) == 0;
}

}  // namespace rig::live::testing
