// foveal/gaze/recording.h — eye-tracker recordings: samples in seconds and screen pixels.
//
// Every reader turns its tracker's layout into the same thing: samples with a time in seconds
// (the tracker's own clock), a gaze point in the recording's *screen pixels* (origin top-left,
// y down), a confidence in [0, 1] and a validity flag. Missing data (EyeLink's ".", Tobii's −1
// with a bad validity code, empty cells) becomes an invalid sample with a NaN point — never a
// zero. Where the recording carries the tracker's own fixation and blink events, they come too.
//
// Coordinates: EyeLink ASC is already in screen pixels (DISPLAY_COORDS / GAZE_COORDS give the
// screen). Normalised formats (Pupil norm_pos, Tobii SDK 2-D gaze, a CSV with --coords norm) are
// scaled by the screen size of ReadOptions (default: the display's resolution). Mapping the
// screen onto a render of another size is ScreenMapping's job (fixation.h), not the reader's.
#pragma once

#include <glm/glm.hpp>

#include <optional>
#include <string>
#include <vector>

namespace foveal {

enum class GazeFormat { automatic, asc, pupil, tobii, csv, bids };
const char* to_string(GazeFormat format);
GazeFormat parse_gaze_format(const std::string& name);  // throws Error for an unknown name

// One gaze sample.
struct GazeSample {
  double t_s = 0;                       // tracker clock, seconds
  glm::dvec2 px{NAN};                   // screen pixels, origin top-left, y down; NaN when the tracker lost the eye
  float confidence = 1;                 // tracker's confidence in [0, 1] (1 where the format has none)
  bool valid = false;                   // finite point, confidence ≥ the minimum, not inside a blink
  std::optional<glm::dvec3> direction;  // gaze direction where the tracker gives one (Pupil's gaze_point_3d)
  float pupil = NAN;                    // pupil size in the tracker's units (EyeLink area or diameter, a CSV's pupil column); NaN if none
};

// An event of the tracker's own (EyeLink EFIX/EBLINK, Pupil fixations.csv/blinks.csv, Tobii Pro Lab).
struct GazeEvent {
  double start_s = 0, end_s = 0;  // tracker clock, seconds, inclusive
  glm::dvec2 px{NAN};             // fixation centre in screen pixels (NaN for blinks)
};

// Which eye of a binocular recording: the average of the valid eyes (Tobii's "Average"), or one.
enum class EyeSelection { average, left, right };
EyeSelection parse_eye_selection(const std::string& name);

// How to read a recording. Units for the plain CSV; screen size for normalised coordinates.
struct ReadOptions {
  GazeFormat format = GazeFormat::automatic;
  glm::ivec2 screen_px{1680, 1050};  // screen for normalised coordinates (unless the file states one)
  bool screen_from_user = false;     // true: screen_px overrides what the file states
  float min_confidence = 0.6f;       // Pupil's default: lower confidence → invalid sample
  EyeSelection eye = EyeSelection::average;
  // Plain CSV only
  double csv_time_scale = 1;    // seconds per unit of the t column (s: 1, ms: 1e-3, us: 1e-6)
  bool csv_normalised = false;  // x, y in [0, 1] of the screen instead of pixels
  bool csv_origin_bottom_left = false;
  bool csv_degrees = false;  // x, y in degrees of visual angle from the screen centre (y up), mapped
                             // through the display below (also columns named x_deg, y_deg)
  double display_width_cm = 47.5, display_height_cm = 30, display_distance_cm = 60;
  // Tracker events from side files (Pupil's fixations.csv / blinks.csv); empty → looked for beside the file
  std::string fixations_file, blinks_file;
  bool find_side_files = true;
};

// A recording: samples in time order plus what the file says about itself.
struct Recording {
  std::string source;  // path (or name given to parse_recording)
  GazeFormat format = GazeFormat::csv;
  std::string tracker;                  // "EyeLink", "Pupil Player export", …
  std::vector<GazeSample> samples;      // time never decreases
  std::vector<size_t> block_starts;     // index of each recording block's first sample (EyeLink START…END)
  glm::ivec2 screen_px{0};              // screen the points are in
  bool screen_from_file = false;        // the file stated the screen size
  std::optional<glm::dvec3> screen_cm;  // the display's width, height and viewing distance, cm, where the file states them (BIDS)
  std::string eyes;                     // "left", "right", "binocular (average)", …
  double nominal_rate_hz = 0;           // as the file states it (EyeLink RATE), else 0
  std::vector<GazeEvent> fixations;     // the tracker's own fixations (empty if none)
  std::vector<GazeEvent> blinks;        // the tracker's own blinks
  bool has_tracker_fixations = false;   // the format carries fixation events (even if there are none)
  std::vector<std::string> notes;       // what the reader did beyond the obvious (side files read, …)
  std::vector<std::string> warnings;    // what the user must hear (a block cut short: the file may be truncated);
                                        // the commands print them on stderr, the data read stays usable

  size_t valid_count() const;
  // Time from the first to the last sample, seconds.
  double duration_s() const;
  // Recorded time: the sum of each block's span (gaps between blocks excluded), seconds.
  double recorded_s() const;
  // Sampling rate: samples per second within blocks, gaps in time (over 10× the median interval) left out.
  double rate_hz() const;
};

// Detect the format from the file's first line(s).
GazeFormat detect_gaze_format(const std::string& text, const std::string& name);

// Read a recording file; throws Error naming the file, line and reason.
Recording read_recording(const std::string& path, const ReadOptions& options = {});
// Parse recording text (side files are not looked for); `name` is used in messages.
Recording parse_recording(const std::string& text, const std::string& name, const ReadOptions& options = {});

// The format readers (text → recording); used by parse_recording.
Recording parse_eyelink_asc(const std::string& text, const std::string& name, const ReadOptions& options);
Recording parse_pupil_gaze(const std::string& text, const std::string& name, const ReadOptions& options);
Recording parse_tobii(const std::string& text, const std::string& name, const ReadOptions& options);
Recording parse_gaze_csv(const std::string& text, const std::string& name, const ReadOptions& options);
// Pupil's fixations.csv (duration in ms) and blinks.csv exports.
std::vector<GazeEvent> parse_pupil_fixations(const std::string& text, const std::string& name, glm::ivec2 screen_px);
std::vector<GazeEvent> parse_pupil_blinks(const std::string& text, const std::string& name);

// Whether a gaze point can be where an eye looked: finite and at most one screen beyond the
// screen's edges (x in [−W, 2W], y in [−H, 2H]). Points beyond are tracker glitches (a norm_pos of
// 1e30), never gaze: the readers and the live sources mark them invalid and count them.
bool plausible_point(glm::dvec2 px, glm::ivec2 screen_px);

// Mark samples inside blinks, below the confidence minimum, or not plausible_point() invalid;
// used by the readers. How many were implausible goes into the recording's notes.
void apply_validity(Recording& recording, float min_confidence);

}  // namespace foveal
