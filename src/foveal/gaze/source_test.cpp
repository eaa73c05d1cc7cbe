// Live gaze over a loopback Pupil Remote + publisher that speaks Pupil's documented wire format
// (REQ "SUB_PORT" → port; multipart [topic, msgpack dict]), including a disconnect mid-stream
// and a tracker that never answers; real-time playback on a fake clock.
#include "foveal/gaze/fixation.h"
#include "foveal/gaze/source.h"
#include "foveal/util/error.h"
#include "fake_pupil.h"

#include <gtest/gtest.h>
#include <msgpack.hpp>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include <chrono>
#include <thread>

using namespace foveal;
using namespace foveal_test;
using Clock = std::chrono::steady_clock;

namespace {

// Poll until `count` samples arrived or the deadline passed.
std::vector<GazeSample> collect(GazeSource& source, size_t count, double seconds = 5) {
  std::vector<GazeSample> out;
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  while (out.size() < count && Clock::now() < deadline) {
    source.poll(out);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return out;
}

template <class F>
bool eventually(F&& condition, double seconds = 5) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

}  // namespace

TEST(Source, PupilUrls) {
  const PupilUrl u = parse_pupil_url("pupil://10.0.0.2:50021?surface=screen&timeout=0.5&stale=0.25");
  EXPECT_EQ(u.host, "10.0.0.2");
  EXPECT_EQ(u.port, 50021);
  EXPECT_EQ(u.topic(), "surfaces.screen");
  EXPECT_DOUBLE_EQ(u.timeout_s, 0.5);
  EXPECT_DOUBLE_EQ(u.stale_s, 0.25);
  EXPECT_EQ(parse_pupil_url("pupil://localhost").port, 50020);
  EXPECT_EQ(parse_pupil_url("pupil://localhost").topic(), "gaze.");
  for (const char* bad :
       {"http://x:1", "pupil://:50020", "pupil://h:99999", "pupil://h:12?colour=red", "pupil://h:1?timeout=-1", "pupil://h:1?surface="})
    EXPECT_THROW(parse_pupil_url(bad), Error) << bad;
}

TEST(Source, DecodesPupilMessages) {
  std::vector<GazeSample> out;
  ASSERT_TRUE(decode_pupil_message("gaze.3d.01.", world_gaze(0.25, 0.75, 0.9, 12.5).data(), world_gaze(0.25, 0.75, 0.9, 12.5).size(),
                                   {1000, 500}, 0.6f, out));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].px, glm::dvec2(250, 125));  // origin bottom-left → top-left
  EXPECT_DOUBLE_EQ(out[0].t_s, 12.5);
  EXPECT_TRUE(out[0].valid);
  const std::string off = surface_gaze(0.5, 0.5, false, 1);
  ASSERT_TRUE(decode_pupil_message("surfaces.screen", off.data(), off.size(), {1000, 500}, 0.6f, out));
  EXPECT_FALSE(out.back().valid);           // off the surface: held, not followed
  const std::string junk = "\x93\x01\x02";  // a msgpack array, not a dict
  EXPECT_FALSE(decode_pupil_message("gaze.", junk.data(), junk.size(), {1000, 500}, 0.6f, out));
  EXPECT_FALSE(decode_pupil_message("gaze.", "\xc1", 1, {1000, 500}, 0.6f, out));  // never-used byte
  EXPECT_FALSE(decode_pupil_message("gaze.", "", 0, {1000, 500}, 0.6f, out));
  // Found by fuzzing: an array header claiming 2^32 − 1 elements must not reserve memory for them
  const std::string huge = "\x81\xa3pos\xdd\xff\xff\xff\xff";
  EXPECT_FALSE(decode_pupil_message("gaze.", huge.data(), huge.size(), {1000, 500}, 0.6f, out));
}

TEST(Source, SurfaceGazeThenDisconnect) {
  FakePupil fake;
  std::vector<std::pair<std::string, std::string>> messages;
  for (int i = 0; i < 20; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.25, 0.75, i != 10, 100 + 0.004 * i));
  std::string subscription;
  fake.serve(messages, true, &subscription);
  PupilSource source(fake.url("surface=screen&timeout=3"), {1680, 1050});
  const std::vector<GazeSample> samples = collect(source, 20);
  ASSERT_EQ(samples.size(), 20u);
  EXPECT_EQ(subscription, "surfaces.screen");
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i].px, glm::dvec2(420, 262.5));
    EXPECT_EQ(samples[i].valid, i != 10);
    EXPECT_DOUBLE_EQ(samples[i].t_s, 100 + 0.004 * i);
  }
  // The publisher hangs up mid-stream: reported within a bounded time, and polling never blocks
  EXPECT_TRUE(eventually([&] { return source.state() == SourceState::disconnected; }));
  const auto start = Clock::now();
  std::vector<GazeSample> more;
  source.poll(more);
  EXPECT_TRUE(more.empty());
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 0.1);
}

TEST(Source, HangUpBehindABurstComesAfterItsSamples) {
  // The hang-up can be seen before the messages sent ahead of it are read: they must neither be
  // lost to a caller that stops at `disconnected` nor make the tracker look connected again
  FakePupil fake;
  fake.pause = std::chrono::milliseconds(0);
  std::vector<std::pair<std::string, std::string>> messages;
  for (int i = 0; i < 900; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.5, 0.5, true, 0.001 * i));
  fake.serve(messages, true, nullptr);
  PupilSource source(fake.url("surface=screen&timeout=3"), {100, 100});
  // Once `disconnected` is reported, one poll hands over everything that came before the hang-up
  // (the publisher's hang-up drops what it had not sent yet: linger 0)
  // (watched without pauses, to catch the moment it turns)
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (source.state() != SourceState::disconnected && Clock::now() < deadline) std::this_thread::yield();
  ASSERT_EQ(source.state(), SourceState::disconnected);
  std::vector<GazeSample> samples;
  source.poll(samples);
  EXPECT_GT(samples.size(), 0u);
  const size_t handed_over = samples.size();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  source.poll(samples);
  EXPECT_EQ(samples.size(), handed_over) << "samples arrived after the hang-up was reported";
  EXPECT_EQ(source.state(), SourceState::disconnected);
  for (size_t i = 0; i < samples.size(); ++i) EXPECT_DOUBLE_EQ(samples[i].t_s, 0.001 * i);  // in order, none lost between
}

TEST(Source, WorldGazeSkipsMalformedAndTurnsStale) {
  FakePupil fake;
  fake.serve({{"gaze.3d.01.", world_gaze(0.5, 0.5, 0.9, 1.0)},
              {"gaze.3d.01.", "not msgpack at all"},
              {"gaze.3d.01.", world_gaze(0.1, 0.9, 0.3, 1.004)},
              {"gaze.3d.01.", "\x92\x01\x02"}},
             false, nullptr);
  PupilSource source(fake.url("stale=0.2"), {1000, 1000});
  const std::vector<GazeSample> samples = collect(source, 2);
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_TRUE(samples[0].valid);
  EXPECT_FALSE(samples[1].valid);  // confidence 0.3 < 0.6
  EXPECT_TRUE(eventually([&] { return source.malformed() == 2; }));
  // Connected but silent: stale, not disconnected
  EXPECT_TRUE(eventually([&] { return source.state() == SourceState::stale; }));
  EXPECT_GT(source.silent_s(), 0.2);
}

TEST(Source, TrackerThatNeverAnswersFailsInBoundedTime) {
  zmq::context_t context;
  zmq::socket_t mute(context, zmq::socket_type::rep);  // accepts, never replies
  mute.set(zmq::sockopt::linger, 0);
  mute.bind("tcp://127.0.0.1:*");
  const auto start = Clock::now();
  try {
    PupilSource source("pupil://127.0.0.1:" + std::to_string(bound_port(mute)) + "?timeout=0.3", {100, 100});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did not answer SUB_PORT within 0.3 s"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 2.0);
  // Nobody listening at all: the same bounded failure
  int free_port = 0;
  {
    zmq::socket_t probe(context, zmq::socket_type::rep);
    probe.set(zmq::sockopt::linger, 0);
    probe.bind("tcp://127.0.0.1:*");
    free_port = bound_port(probe);
  }
  const auto start2 = Clock::now();
  EXPECT_THROW(PupilSource("pupil://127.0.0.1:" + std::to_string(free_port) + "?timeout=0.3", {100, 100}), Error);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start2).count(), 2.0);
}

TEST(Source, RecordingPlaysBackInRealTime) {
  Recording r;
  r.screen_px = {100, 100};
  for (int i = 0; i < 10; ++i) r.samples.push_back(GazeSample{50.0 + 0.1 * i, glm::dvec2(i, i), 1, true, {}});
  double now = 0;
  RecordingPlayback playback(r, 2.0, [&] { return now; });
  std::vector<GazeSample> out;
  playback.poll(out);
  EXPECT_EQ(out.size(), 1u);  // the first sample is due at once
  now = 0.2;                  // 0.4 s of recording at double speed
  playback.poll(out);
  EXPECT_EQ(out.size(), 5u);
  EXPECT_EQ(playback.state(), SourceState::live);
  now = 10;
  playback.poll(out);
  EXPECT_EQ(out.size(), 10u);
  EXPECT_EQ(playback.state(), SourceState::ended);
  MouseSource mouse({640, 480});
  EXPECT_EQ(mouse.state(), SourceState::waiting);
  mouse.move({10, 20}, 0.5);
  mouse.move({-1, -1}, 0.6, false);
  out.clear();
  mouse.poll(out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].valid);
  EXPECT_FALSE(out[1].valid);
}

// A glitch far off the surface (norm_pos [1e30, -5] with on_surf true) is no gaze point: it is
// invalid, carries no point, is counted, and the valid samples around it still make a fixation.
TEST(Source, AbsurdGazeIsInvalidAndCounted) {
  FakePupil fake;
  std::vector<std::pair<std::string, std::string>> messages;
  for (int i = 0; i < 60; ++i)
    messages.emplace_back("surfaces.screen", i == 30 ? surface_gaze(1e30, -5, true, 0.004 * i) : surface_gaze(0.5, 0.5, true, 0.004 * i));
  messages.emplace_back("surfaces.screen", surface_gaze(-1.5, 0.5, true, 0.24));   // one screen and a half to the left
  messages.emplace_back("surfaces.screen", surface_gaze(1.9, -0.9, true, 0.244));  // off the screen, within one screen: kept
  fake.serve(messages, false, nullptr);
  PupilSource source(fake.url("surface=screen&timeout=3"), {1000, 500});
  const std::vector<GazeSample> samples = collect(source, 62);
  ASSERT_EQ(samples.size(), 62u);
  EXPECT_FALSE(samples[30].valid);
  EXPECT_TRUE(std::isnan(samples[30].px.x));
  EXPECT_FALSE(samples[60].valid);
  EXPECT_TRUE(samples[61].valid);
  EXPECT_EQ(source.implausible(), 2u);
  // The samples around the glitch still become one fixation
  Recording r;
  r.screen_px = {1000, 500};
  r.samples.assign(samples.begin(), samples.begin() + 60);
  const FixationResult f = detect_ivt(r, GazeGeometry(Display{47.5, 30, 60, 1000, 500}, r.screen_px), {});
  EXPECT_EQ(f.fixations.size(), 1u);
}
