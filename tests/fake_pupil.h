// tests/fake_pupil.h — a loopback Pupil Capture for tests: Pupil Remote (REQ/REP, answers
// "SUB_PORT") and the IPC backbone's publisher (multipart [topic, msgpack dict]), as documented
// for Pupil Core's Network API.
#pragma once

#include <msgpack.hpp>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include <chrono>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace foveal_test {

inline int bound_port(zmq::socket_t& s) {
  const std::string endpoint = s.get(zmq::sockopt::last_endpoint);
  return std::stoi(endpoint.substr(endpoint.rfind(':') + 1));
}

inline std::string world_gaze(double x, double y, double confidence, double t) {
  msgpack::sbuffer buffer;
  msgpack::packer<msgpack::sbuffer> pk(&buffer);
  pk.pack_map(4);
  pk.pack(std::string("topic"));
  pk.pack(std::string("gaze.3d.01."));
  pk.pack(std::string("norm_pos"));
  pk.pack_array(2);
  pk.pack(x);
  pk.pack(y);
  pk.pack(std::string("confidence"));
  pk.pack(confidence);
  pk.pack(std::string("timestamp"));
  pk.pack(t);
  return {buffer.data(), buffer.size()};
}

inline std::string surface_gaze(double x, double y, bool on_surf, double t) {
  msgpack::sbuffer buffer;
  msgpack::packer<msgpack::sbuffer> pk(&buffer);
  pk.pack_map(3);
  pk.pack(std::string("name"));
  pk.pack(std::string("screen"));
  pk.pack(std::string("timestamp"));
  pk.pack(t);
  pk.pack(std::string("gaze_on_surfaces"));
  pk.pack_array(1);
  pk.pack_map(4);
  pk.pack(std::string("norm_pos"));
  pk.pack_array(2);
  pk.pack(x);
  pk.pack(y);
  pk.pack(std::string("on_surf"));
  pk.pack(on_surf);
  pk.pack(std::string("confidence"));
  pk.pack(0.95);
  pk.pack(std::string("timestamp"));
  pk.pack(t);
  return {buffer.data(), buffer.size()};
}

// Pupil Remote (REP) and the IPC backbone's publisher (XPUB, to see the subscription arrive).
struct FakePupil {
  zmq::context_t context{1};
  zmq::socket_t remote{context, zmq::socket_type::rep};
  zmq::socket_t pub{context, zmq::socket_type::xpub};
  int remote_port = 0, pub_port = 0;
  std::chrono::milliseconds pause{1};  // between messages; 0 sends a burst
  std::thread thread;

  FakePupil() {
    for (zmq::socket_t* s : {&remote, &pub}) {
      s->set(zmq::sockopt::linger, 0);
      s->set(zmq::sockopt::rcvtimeo, 5000);
    }
    remote.bind("tcp://127.0.0.1:*");
    pub.bind("tcp://127.0.0.1:*");
    remote_port = bound_port(remote);
    pub_port = bound_port(pub);
  }
  ~FakePupil() {
    if (thread.joinable()) thread.join();
  }
  std::string url(const std::string& query = "") const {
    return "pupil://127.0.0.1:" + std::to_string(remote_port) + (query.empty() ? "" : "?" + query);
  }
  // Answer SUB_PORT, wait for the subscription, publish the messages, then optionally hang up.
  void serve(std::vector<std::pair<std::string, std::string>> messages, bool hang_up, std::string* subscription) {
    thread = std::thread([this, messages = std::move(messages), hang_up, subscription] {
      zmq::message_t request;
      if (!remote.recv(request)) return;
      remote.send(zmq::buffer(std::to_string(pub_port)), zmq::send_flags::none);
      zmq::message_t sub;
      if (!pub.recv(sub)) return;  // "\x01" + topic
      if (subscription) *subscription = sub.to_string().substr(1);
      for (const auto& [topic, payload] : messages) {
        pub.send(zmq::buffer(topic), zmq::send_flags::sndmore);
        pub.send(zmq::buffer(payload), zmq::send_flags::none);
        if (pause.count() > 0) std::this_thread::sleep_for(pause);
      }
      if (hang_up) {
        pub.close();
        remote.close();
      }
    });
  }
};

}  // namespace foveal_test
