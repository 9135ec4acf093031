#include "rig/live/http_server.hpp"

#include <fmt/format.h>
#include <httplib.h>
#include <sys/socket.h>

#include <atomic>
#include <charconv>
#include <random>
#include <stdexcept>
#include <thread>

namespace rig::live {
namespace {

// A stream with nothing new sends a comment this often, so that a browser that went away is
// noticed (the write fails) and its thread freed.
constexpr auto kKeepAlive = std::chrono::milliseconds(1000);
// A browser that stops reading blocks only its own write, for at most this long.
constexpr int kWriteTimeoutS = 5;

int parse_port(const std::string& text, const std::string& whole) {
  int port = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), port);
  if (ec != std::errc() || end != text.data() + text.size() || port < 0 || port > 65535) {
    throw std::invalid_argument(
        fmt::format("--http {}: expected HOST:PORT or PORT with PORT in 0..65535", whole));
  }
  return port;
}

// Equal-time comparison: the time a wrong token takes says nothing of the right one.
bool same_token(const std::string& a, const std::string& b) {
  if (a.size() != b.size() || a.empty()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string sse(const Message& m) {
  return fmt::format("id: {}\nevent: {}\ndata: {}\n\n", m.seq, m.kind, m.json);
}

// A batch as server-sent events, consecutive samples grouped into one "samples" event whose
// data is their array: a page opened late parses hours of samples at once instead of one
// event each (94 000 events took a browser 2 s; the groups take a fraction of that).
std::string sse_batch(const std::vector<MessagePtr>& batch) {
  std::string out;
  std::size_t i = 0;
  while (i < batch.size()) {
    if (batch[i]->kind != kind::kSample) {
      out += sse(*batch[i++]);
      continue;
    }
    std::string data = "[";
    std::uint64_t last = 0;
    for (; i < batch.size() && batch[i]->kind == kind::kSample; ++i) {
      if (data.size() > 1) data += ',';
      data += batch[i]->json;
      last = batch[i]->seq;
    }
    out += fmt::format("id: {}\nevent: samples\ndata: {}]\n\n", last, data);
  }
  return out;
}

}  // namespace

HttpAddress parse_http_address(const std::string& text) {
  HttpAddress a;
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) {
    a.port = parse_port(text, text);
  } else {
    a.host = text.substr(0, colon);
    if (a.host.empty()) throw std::invalid_argument("--http " + text + ": the host is empty");
    a.port = parse_port(text.substr(colon + 1), text);
  }
  return a;
}

std::string new_stop_token() {
  std::random_device rd;
  std::string token;
  for (int i = 0; i < 4; ++i) token += fmt::format("{:08x}", rd());
  return token;
}

struct LiveServer::Impl {
  const Feed& feed;
  std::string token;
  std::string page;
  std::function<void()> on_stop;
  httplib::Server server;
  std::thread thread;
  std::atomic<bool> stopping{false};
  std::atomic<int> streams{0};  // event streams being served

  Impl(const Feed& f, std::string t, std::string p, std::function<void()> s)
      : feed(f), token(std::move(t)), page(std::move(p)), on_stop(std::move(s)) {}

  void routes();
  void events(const httplib::Request& req, httplib::Response& res);
  void state(httplib::Response& res) const;
  void stop_request(const httplib::Request& req, httplib::Response& res);
};

void LiveServer::Impl::routes() {
  server.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(page, "text/html; charset=utf-8");
  });
  server.Get("/events",
             [this](const httplib::Request& req, httplib::Response& res) { events(req, res); });
  server.Get("/state", [this](const httplib::Request&, httplib::Response& res) { state(res); });
  server.Post("/stop", [this](const httplib::Request& req, httplib::Response& res) {
    stop_request(req, res);
  });
}

void LiveServer::Impl::events(const httplib::Request& req, httplib::Response& res) {
  std::uint64_t after = 0;
  if (req.has_header("Last-Event-ID")) {
    const std::string id = req.get_header_value("Last-Event-ID");
    std::from_chars(id.data(), id.data() + id.size(), after);
  }
  res.set_header("Cache-Control", "no-store");
  ++streams;
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, after](std::size_t, httplib::DataSink& sink) mutable {
        while (!stopping.load()) {
          const auto batch = feed.since(after);
          if (!batch.empty()) {
            const std::string chunk = sse_batch(batch);
            after = batch.back()->seq;
            if (!sink.write(chunk.data(), chunk.size())) return false;
            continue;
          }
          if (feed.closed()) break;
          if (!feed.wait(after, kKeepAlive) && !sink.write(": keep-alive\n\n", 14)) return false;
        }
        sink.done();
        return true;
      },
      [this](bool) { --streams; });
}

void LiveServer::Impl::state(httplib::Response& res) const {
  std::string body = "{";
  const char* sep = "";
  for (const char* k : {kind::kStart, kind::kState, kind::kOutcome}) {
    const MessagePtr m = feed.latest(k);
    body += fmt::format("{}\"{}\":{}", sep, k, m ? m->json : "null");
    sep = ",";
  }
  res.set_header("Cache-Control", "no-store");
  res.set_content(body + "}", "application/json");
}

void LiveServer::Impl::stop_request(const httplib::Request& req, httplib::Response& res) {
  std::string given = req.get_header_value("X-Rig-Token");
  if (given.empty() && req.has_param("token")) given = req.get_param_value("token");
  if (!same_token(given, token)) {
    res.status = 403;
    res.set_content(R"({"stopping":false,"error":"the stop needs this run's token"})",
                    "application/json");
    return;
  }
  res.status = 202;
  res.set_content(R"({"stopping":true})", "application/json");
  on_stop();
}

LiveServer::LiveServer(const Feed& feed, const HttpAddress& address, std::string token,
                       std::string title, std::function<void()> on_stop)
    : impl_(std::make_unique<Impl>(feed, std::move(token), live_page_html(title),
                                   std::move(on_stop))) {
  impl_->routes();
  impl_->server.set_write_timeout(kWriteTimeoutS, 0);
  // SO_REUSEADDR only: cpp-httplib's default also sets SO_REUSEPORT, which would let a second
  // rig bind the same port and take half of the first one's visitors.
  impl_->server.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  int port = address.port;
  if (port == 0) {
    port = impl_->server.bind_to_any_port(address.host);
  } else if (!impl_->server.bind_to_port(address.host, port)) {
    port = -1;
  }
  if (port <= 0) {
    throw std::runtime_error(
        fmt::format("--http {}:{}: cannot listen there (address in use, or "
                    "not an address of this machine)",
                    address.host, address.port));
  }
  url_ = fmt::format("http://{}:{}/", address.host, port);
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
  // Serving before returning: cpp-httplib's stop() does nothing to a server whose thread has
  // not reached its accept loop yet, which would then never end (and stop() never join).
  for (int i = 0; i < 2000 && !impl_->server.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void LiveServer::stop() {
  if (!impl_ || impl_->stopping.load()) return;
  // A closed feed's last messages (the outcome) reach the pages still connected first.
  constexpr int kDrainWaits = 20;  // of 50 ms
  for (int i = 0; i < kDrainWaits && impl_->feed.closed() && impl_->streams.load() > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  impl_->stopping.store(true);
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

LiveServer::~LiveServer() { stop(); }

}  // namespace rig::live
