// foveal/gaze/source.cpp — live and played-back gaze sources.
#include "foveal/gaze/source.h"

#include "foveal/util/error.h"

#include <msgpack.hpp>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

namespace foveal {

const char* to_string(SourceState s) {
  switch (s) {
    case SourceState::waiting:
      return "waiting";
    case SourceState::live:
      return "live";
    case SourceState::stale:
      return "stale";
    case SourceState::disconnected:
      return "disconnected";
    case SourceState::ended:
      return "ended";
  }
  return "?";
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Pupil URL and messages

PupilUrl parse_pupil_url(const std::string& url) {
  const std::string scheme = "pupil://";
  if (url.rfind(scheme, 0) != 0) fail("{}: a live tracker URL starts with pupil://", url);
  PupilUrl u;
  std::string rest = url.substr(scheme.size()), query;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (!rest.empty() && rest.back() == '/') rest.pop_back();
  if (const auto colon = rest.rfind(':'); colon != std::string::npos) {
    u.host = rest.substr(0, colon);
    const std::string port = rest.substr(colon + 1);
    char* end = nullptr;
    const long p = std::strtol(port.c_str(), &end, 10);
    if (port.empty() || *end != '\0' || p < 1 || p > 65535) fail("{}: port '{}' is not a number in 1..65535", url, port);
    u.port = static_cast<int>(p);
  } else if (!rest.empty()) {
    u.host = rest;
  }
  if (u.host.empty()) fail("{}: no host (expected pupil://HOST:PORT)", url);
  size_t start = 0;
  while (start < query.size()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string item = query.substr(start, end - start);
    start = end + 1;
    const auto eq = item.find('=');
    const std::string key = item.substr(0, eq), value = eq == std::string::npos ? "" : item.substr(eq + 1);
    auto seconds = [&] {
      char* e = nullptr;
      const double v = std::strtod(value.c_str(), &e);
      if (value.empty() || *e != '\0' || !(v > 0) || !std::isfinite(v)) fail("{}: {} must be a positive number of seconds", url, key);
      return v;
    };
    if (key == "surface") {
      if (value.empty()) fail("{}: surface= needs a surface name", url);
      u.surface = value;
    } else if (key == "timeout") {
      u.timeout_s = seconds();
    } else if (key == "stale") {
      u.stale_s = seconds();
    } else {
      fail("{}: unknown parameter '{}' (expected surface, timeout or stale)", url, key);
    }
  }
  return u;
}

namespace {

const msgpack::object* field(const msgpack::object& map, std::string_view key) {
  if (map.type != msgpack::type::MAP) return nullptr;
  for (uint32_t i = 0; i < map.via.map.size; ++i) {
    const msgpack::object_kv& kv = map.via.map.ptr[i];
    if (kv.key.type == msgpack::type::STR && std::string_view(kv.key.via.str.ptr, kv.key.via.str.size) == key) return &kv.val;
  }
  return nullptr;
}

std::optional<double> number(const msgpack::object* o) {
  if (!o) return std::nullopt;
  switch (o->type) {
    case msgpack::type::POSITIVE_INTEGER:
      return static_cast<double>(o->via.u64);
    case msgpack::type::NEGATIVE_INTEGER:
      return static_cast<double>(o->via.i64);
    case msgpack::type::FLOAT32:
    case msgpack::type::FLOAT64:
      return std::isfinite(o->via.f64) ? std::optional<double>(o->via.f64) : std::nullopt;
    default:
      return std::nullopt;
  }
}

// One datum with norm_pos / confidence / timestamp (and on_surf for surface gaze).
bool decode_datum(const msgpack::object& d, glm::ivec2 screen, float min_confidence, bool surface, std::vector<GazeSample>& out) {
  const msgpack::object* pos = field(d, "norm_pos");
  if (!pos || pos->type != msgpack::type::ARRAY || pos->via.array.size < 2) return false;
  const auto x = number(&pos->via.array.ptr[0]), y = number(&pos->via.array.ptr[1]);
  const auto t = number(field(d, "timestamp"));
  if (!x || !y || !t) return false;
  GazeSample s;
  s.t_s = *t;
  s.px = {*x * screen.x, (1.0 - *y) * screen.y};  // Pupil: origin bottom-left
  s.confidence = static_cast<float>(number(field(d, "confidence")).value_or(1.0));
  bool on_surface = true;
  if (surface) {
    const msgpack::object* on = field(d, "on_surf");
    if (!on || on->type != msgpack::type::BOOLEAN) return false;
    on_surface = on->via.boolean;
  }
  s.valid = on_surface && s.confidence >= min_confidence;
  if (!plausible_point(s.px, screen)) {  // a glitch far off the screen (PupilSource counts them)
    s.px = glm::dvec2(NAN);
    s.valid = false;
  }
  out.push_back(s);
  return true;
}

}  // namespace

bool decode_pupil_message(const std::string& topic, const void* payload, size_t size, glm::ivec2 screen, float min_confidence,
                          std::vector<GazeSample>& out) {
  try {
    // No container can hold more elements than the payload has bytes: a corrupt length must not
    // make the unpacker reserve gigabytes before it finds out.
    const msgpack::unpack_limit limit(size, size, size, size, size, 32);
    const msgpack::object_handle handle = msgpack::unpack(static_cast<const char*>(payload), size, nullptr, nullptr, limit);
    const msgpack::object& root = handle.get();
    if (root.type != msgpack::type::MAP) return false;
    if (topic.rfind("surfaces.", 0) == 0) {
      const msgpack::object* list = field(root, "gaze_on_surfaces");
      if (!list || list->type != msgpack::type::ARRAY) return false;
      const size_t before = out.size();
      for (uint32_t i = 0; i < list->via.array.size; ++i)
        if (!decode_datum(list->via.array.ptr[i], screen, min_confidence, true, out)) {
          out.resize(before);
          return false;
        }
      return true;
    }
    return decode_datum(root, screen, min_confidence, false, out);
  } catch (const std::exception&) {
    return false;  // msgpack::unpack_error, type_error, insufficient_bytes, …
  }
}

// ---------------------------------------------------------------------------------------------
// PupilSource

struct PupilSource::Impl {
  zmq::context_t context{1};
  zmq::socket_t sub, monitor;
  std::thread thread;
  std::atomic<bool> stop{false};
  mutable std::mutex mutex;
  std::vector<GazeSample> pending;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now(), last = start;
  bool any = false, disconnected = false;
  size_t malformed = 0, received = 0, implausible = 0;
  double stale_s = 0.5;

  // One message from the subscriber, if one is there; false when none is.
  bool read_one(glm::ivec2 screen, float min_confidence, std::vector<GazeSample>& decoded) {
    std::vector<zmq::message_t> parts;
    if (!zmq::recv_multipart(sub, std::back_inserter(parts), zmq::recv_flags::dontwait)) return false;
    decoded.clear();
    const bool ok =
        parts.size() >= 2 && decode_pupil_message(parts[0].to_string(), parts[1].data(), parts[1].size(), screen, min_confidence, decoded);
    const std::lock_guard lock(mutex);
    ++received;
    if (!ok) {
      ++malformed;
    } else {
      for (const GazeSample& s : decoded) implausible += !std::isfinite(s.px.x);
      pending.insert(pending.end(), decoded.begin(), decoded.end());
      last = std::chrono::steady_clock::now();
      any = true;
    }
    return true;
  }
  // Every message there is now (until stopped).
  void drain(glm::ivec2 screen, float min_confidence, std::vector<GazeSample>& decoded) {
    while (!stop.load() && read_one(screen, min_confidence, decoded)) {}
  }

  void run(glm::ivec2 screen, float min_confidence) {
    zmq::pollitem_t items[] = {{sub.handle(), 0, ZMQ_POLLIN, 0}, {monitor.handle(), 0, ZMQ_POLLIN, 0}};
    zmq::pollitem_t sub_only[] = {{sub.handle(), 0, ZMQ_POLLIN, 0}};
    std::vector<GazeSample> decoded;
    while (!stop.load()) {
      try {
        zmq::poll(items, 2, std::chrono::milliseconds(50));
        if (items[0].revents & ZMQ_POLLIN) drain(screen, min_confidence, decoded);
        if (items[1].revents & ZMQ_POLLIN) {
          std::vector<zmq::message_t> event;
          if (zmq::recv_multipart(monitor, std::back_inserter(event), zmq::recv_flags::dontwait) && !event.empty() &&
              event[0].size() >= sizeof(uint16_t)) {
            uint16_t id = 0;
            std::memcpy(&id, event[0].data(), sizeof id);
            if (id == ZMQ_EVENT_DISCONNECTED) {
              // What the tracker sent before it hung up is still on its way to this socket: read it
              // all (until 50 ms pass without a message), so that a caller that sees
              // `disconnected` and then polls has every sample
              while (!stop.load() && zmq::poll(sub_only, 1, std::chrono::milliseconds(50)) > 0) drain(screen, min_confidence, decoded);
              const std::lock_guard lock(mutex);
              disconnected = true;
            } else if (id == ZMQ_EVENT_CONNECTED) {
              // Only this says the tracker is back: messages sent before a hang-up can be read after it
              const std::lock_guard lock(mutex);
              disconnected = false;
            }
          }
        }
      } catch (const zmq::error_t&) {
        if (stop.load()) break;
      }
    }
  }
};

PupilSource::PupilSource(const std::string& url, glm::ivec2 screen_px, float min_confidence)
    : impl_(std::make_unique<Impl>()), url_(url), screen_(screen_px) {
  const PupilUrl u = parse_pupil_url(url);
  impl_->stale_s = u.stale_s;
  const int timeout_ms = static_cast<int>(std::ceil(u.timeout_s * 1000));
  const std::string remote = fmt::format("tcp://{}:{}", u.host, u.port);
  std::string sub_port;
  try {
    // Ask Pupil Remote where its IPC backbone publishes
    zmq::socket_t req(impl_->context, zmq::socket_type::req);
    req.set(zmq::sockopt::linger, 0);
    req.set(zmq::sockopt::rcvtimeo, timeout_ms);
    req.set(zmq::sockopt::sndtimeo, timeout_ms);
    req.connect(remote);
    if (!req.send(zmq::str_buffer("SUB_PORT"), zmq::send_flags::none))
      fail("{}: cannot send to Pupil Remote at {} within {:g} s", url, remote, u.timeout_s);
    zmq::message_t reply;
    if (!req.recv(reply, zmq::recv_flags::none))
      fail("{}: Pupil Remote at {} did not answer SUB_PORT within {:g} s (is Pupil Capture running with Pupil Remote on that port?)", url,
           remote, u.timeout_s);
    sub_port = reply.to_string();
  } catch (const zmq::error_t& e) {
    fail("{}: cannot reach Pupil Remote at {}: {}", url, remote, e.what());
  }
  char* end = nullptr;
  const long port = std::strtol(sub_port.c_str(), &end, 10);
  if (sub_port.empty() || *end != '\0' || port < 1 || port > 65535)
    fail("{}: Pupil Remote answered SUB_PORT with '{}', not a port number", url, sub_port.substr(0, 40));
  try {
    impl_->sub = zmq::socket_t(impl_->context, zmq::socket_type::sub);
    impl_->sub.set(zmq::sockopt::linger, 0);
    const std::string monitor_endpoint = fmt::format("inproc://pupil-monitor-{}", static_cast<const void*>(impl_.get()));
    if (zmq_socket_monitor(impl_->sub.handle(), monitor_endpoint.c_str(), ZMQ_EVENT_CONNECTED | ZMQ_EVENT_DISCONNECTED) != 0)
      fail("{}: cannot monitor the connection: {}", url, zmq_strerror(zmq_errno()));
    impl_->monitor = zmq::socket_t(impl_->context, zmq::socket_type::pair);
    impl_->monitor.set(zmq::sockopt::linger, 0);
    impl_->monitor.connect(monitor_endpoint);
    impl_->sub.set(zmq::sockopt::subscribe, u.topic());
    impl_->sub.connect(fmt::format("tcp://{}:{}", u.host, port));
  } catch (const zmq::error_t& e) {
    fail("{}: cannot subscribe to {}:{}: {}", url, u.host, port, e.what());
  }
  impl_->thread = std::thread([impl = impl_.get(), screen_px, min_confidence] { impl->run(screen_px, min_confidence); });
}

PupilSource::~PupilSource() {
  impl_->stop = true;
  if (impl_->thread.joinable()) impl_->thread.join();
  impl_->sub.close();
  impl_->monitor.close();
}

void PupilSource::poll(std::vector<GazeSample>& out) {
  const std::lock_guard lock(impl_->mutex);
  out.insert(out.end(), impl_->pending.begin(), impl_->pending.end());
  impl_->pending.clear();
}

SourceState PupilSource::state() const {
  const std::lock_guard lock(impl_->mutex);
  if (impl_->disconnected) return SourceState::disconnected;
  if (!impl_->any) return SourceState::waiting;
  return seconds_since(impl_->last) > impl_->stale_s ? SourceState::stale : SourceState::live;
}

double PupilSource::silent_s() const {
  const std::lock_guard lock(impl_->mutex);
  return seconds_since(impl_->last);
}

size_t PupilSource::malformed() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->malformed;
}

size_t PupilSource::implausible() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->implausible;
}

size_t PupilSource::received() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->received;
}

// ---------------------------------------------------------------------------------------------
// RecordingPlayback

RecordingPlayback::RecordingPlayback(Recording recording, double speed, Clock clock)
    : recording_(std::move(recording)), speed_(speed), clock_(std::move(clock)) {
  if (!(speed_ > 0) || !std::isfinite(speed_)) fail("playback speed must be positive, got {}", speed_);
  if (!clock_) {
    const auto origin = std::chrono::steady_clock::now();
    clock_ = [origin] { return seconds_since(origin); };
  }
  start_ = clock_();
}

void RecordingPlayback::poll(std::vector<GazeSample>& out) {
  if (recording_.samples.empty()) return;
  const double now = recording_.samples.front().t_s + (clock_() - start_) * speed_;
  while (next_ < recording_.samples.size() && recording_.samples[next_].t_s <= now) out.push_back(recording_.samples[next_++]);
}

SourceState RecordingPlayback::state() const {
  if (next_ >= recording_.samples.size()) return SourceState::ended;
  return next_ == 0 ? SourceState::waiting : SourceState::live;
}

double RecordingPlayback::silent_s() const {
  if (next_ == 0 || recording_.samples.empty()) return clock_() - start_;
  const double now = recording_.samples.front().t_s + (clock_() - start_) * speed_;
  return (now - recording_.samples[next_ - 1].t_s) / speed_;
}

// ---------------------------------------------------------------------------------------------
// MouseSource

MouseSource::MouseSource(glm::ivec2 screen_px) : screen_(screen_px), start_(std::chrono::steady_clock::now()), last_(start_) {}

void MouseSource::move(glm::dvec2 px, double t_s, bool inside) {
  const std::lock_guard lock(mutex_);
  GazeSample s;
  s.t_s = t_s;
  s.px = inside ? px : glm::dvec2(NAN);
  s.valid = inside && std::isfinite(px.x) && std::isfinite(px.y);
  if (!pending_.empty() && t_s < pending_.back().t_s) s.t_s = pending_.back().t_s;  // keep time order
  pending_.push_back(s);
  last_ = std::chrono::steady_clock::now();
  any_ = true;
}

void MouseSource::poll(std::vector<GazeSample>& out) {
  const std::lock_guard lock(mutex_);
  out.insert(out.end(), pending_.begin(), pending_.end());
  pending_.clear();
}

SourceState MouseSource::state() const {
  const std::lock_guard lock(mutex_);
  return any_ ? SourceState::live : SourceState::waiting;
}

double MouseSource::silent_s() const {
  const std::lock_guard lock(mutex_);
  return seconds_since(last_);
}

}  // namespace foveal
