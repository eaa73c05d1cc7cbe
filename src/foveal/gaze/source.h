// foveal/gaze/source.h — gaze that arrives while rendering: Pupil Core's Network API (ZeroMQ +
// msgpack), a recording played back in real time, the mouse (for the viewer).
//
// A source is polled, never waited on: poll() hands over what has arrived and returns at once,
// so a tracker that is slow, silent or gone cannot stall a render loop; status() says which.
#pragma once

#include "foveal/gaze/recording.h"

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace foveal {

enum class SourceState {
  waiting,       // connected (or started), nothing received yet
  live,          // samples are arriving
  stale,         // nothing for longer than the stale time (slow tracker?)
  disconnected,  // the tracker closed the connection
  ended,         // a recording has played to its end
};
const char* to_string(SourceState state);

class GazeSource {
 public:
  virtual ~GazeSource() = default;
  // Append the samples that arrived since the last call, in time order (never blocks).
  virtual void poll(std::vector<GazeSample>& out) = 0;
  // disconnected and ended are reported only once every sample that came before them is in the
  // buffer poll() hands over: a caller that sees either and then polls has them all.
  virtual SourceState state() const = 0;
  // Seconds since the last sample arrived (since the start when none has).
  virtual double silent_s() const = 0;
  virtual std::string name() const = 0;
  virtual glm::ivec2 screen_px() const = 0;
};

// Pupil Core / Pupil Capture over its Network API.
//   pupil://HOST:PORT                 gaze in world-camera coordinates (topic "gaze.")
//   pupil://HOST:PORT?surface=NAME    gaze mapped onto a surface tracker surface (topic "surfaces.NAME")
// Optional query keys: timeout=SECONDS (wait for Pupil Remote's SUB_PORT answer, default 2),
// stale=SECONDS (silence before the state turns stale, default 0.5).
struct PupilUrl {
  std::string host = "127.0.0.1";
  int port = 50020;
  std::string surface;  // empty: world-camera gaze
  double timeout_s = 2.0;
  double stale_s = 0.5;
  std::string topic() const { return surface.empty() ? "gaze." : "surfaces." + surface; }
};
PupilUrl parse_pupil_url(const std::string& url);  // throws Error naming the URL

// Opens the connection in the constructor (asks Pupil Remote for SUB_PORT with a bounded wait,
// throws Error if it does not answer) and receives on a background thread.
// Samples: norm_pos (origin bottom-left) × screen_px, confidence, Pupil's timestamp in seconds;
// surface gaze with on_surf == false, or confidence below the minimum, is an invalid sample.
class PupilSource final : public GazeSource {
 public:
  PupilSource(const std::string& url, glm::ivec2 screen_px, float min_confidence = 0.6f);
  ~PupilSource() override;
  PupilSource(const PupilSource&) = delete;
  PupilSource& operator=(const PupilSource&) = delete;

  void poll(std::vector<GazeSample>& out) override;
  SourceState state() const override;
  double silent_s() const override;
  std::string name() const override { return url_; }
  glm::ivec2 screen_px() const override { return screen_; }
  // Messages that could not be read (not a msgpack map, missing fields); they are skipped.
  size_t malformed() const;
  size_t received() const;
  // Samples whose point was not plausible_point() (non-finite, or far off the screen): invalid.
  size_t implausible() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string url_;
  glm::ivec2 screen_;
};

// Decode one Pupil message (topic + msgpack payload) into samples; false if it is malformed.
bool decode_pupil_message(const std::string& topic, const void* payload, size_t size, glm::ivec2 screen_px, float min_confidence,
                          std::vector<GazeSample>& out);

// A recording played back in real time (optionally faster or slower): poll() returns the samples
// whose time, counted from the first, has passed on the clock.
class RecordingPlayback final : public GazeSource {
 public:
  using Clock = std::function<double()>;  // seconds; default: a steady clock
  explicit RecordingPlayback(Recording recording, double speed = 1.0, Clock clock = {});
  void poll(std::vector<GazeSample>& out) override;
  SourceState state() const override;
  double silent_s() const override;
  std::string name() const override { return recording_.source; }
  glm::ivec2 screen_px() const override { return recording_.screen_px; }

 private:
  Recording recording_;
  double speed_;
  Clock clock_;
  double start_;
  size_t next_ = 0;
};

// The mouse as a gaze source (the viewer feeds it cursor positions in screen pixels).
class MouseSource final : public GazeSource {
 public:
  explicit MouseSource(glm::ivec2 screen_px);
  // Record the cursor at time t (seconds); a position off the window is an invalid sample.
  void move(glm::dvec2 px, double t_s, bool inside = true);
  void poll(std::vector<GazeSample>& out) override;
  SourceState state() const override;
  double silent_s() const override;
  std::string name() const override { return "mouse"; }
  glm::ivec2 screen_px() const override { return screen_; }

 private:
  mutable std::mutex mutex_;
  std::vector<GazeSample> pending_;
  glm::ivec2 screen_;
  std::chrono::steady_clock::time_point start_, last_;
  bool any_ = false;
};

}  // namespace foveal
