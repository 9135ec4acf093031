// The live page of a running test or monitor (--http, docs/live.md), served with cpp-httplib
// on its own threads from the live feed (feed.hpp): nothing here runs on the tick loop, and a
// slow or stalled browser only ever holds its own connection's thread.
//
//   GET  /        the page (uPlot embedded, like report.html; redraws itself)
//   GET  /events  server-sent events: the feed's history, then every new message (id: seq,
//                 event: kind, data: JSON); a reconnecting browser resumes after Last-Event-ID
//   GET  /state   {"start", "state", "outcome"}: the latest of each, for scripts
//   POST /stop    what Ctrl-C does for the command, only with the run's token (header
//                 X-Rig-Token or form field token); 403 without it
// Nothing else: the page can neither raise the excitation nor change a limit.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "rig/live/feed.hpp"

namespace rig::live {

struct HttpAddress {
  std::string host = "127.0.0.1";  // loopback unless told otherwise
  int port = 8080;                 // 0: any free port (the URL printed says which)
};

// "HOST:PORT" or "PORT". Throws std::invalid_argument naming --http and what was expected.
HttpAddress parse_http_address(const std::string& text);

// 128 random bits as 32 hex digits, from std::random_device.
std::string new_stop_token();

class LiveServer {
 public:
  // Binds (throws std::runtime_error naming the address when it cannot) and starts serving.
  // on_stop runs on a server thread when POST /stop carries the token.
  LiveServer(const Feed& feed, const HttpAddress& address, std::string token, std::string title,
             std::function<void()> on_stop);
  ~LiveServer();
  LiveServer(const LiveServer&) = delete;
  LiveServer& operator=(const LiveServer&) = delete;

  // The address actually bound, as http://HOST:PORT/.
  const std::string& url() const { return url_; }
  // Ends every event stream and stops serving (the destructor calls it).
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string url_;
};

// The page itself (live_page.cpp).
std::string live_page_html(const std::string& title);

}  // namespace rig::live
