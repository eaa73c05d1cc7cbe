// foveal/gaze/bids.h — BIDS eye tracking (BIDS 1.10+, the physio "eyetrack" files), read and written.
//
// A recording is `sub-S[_ses-X]_task-T[_run-N]_recording-eye1_physio.tsv.gz` (gzip, tab-separated, no
// header) with its sidecar `…_physio.json`: PhysioType "eyetrack", SamplingFrequency, StartTime,
// Columns (timestamp, x_coordinate, y_coordinate first; then pupil_size and foveal's additional
// columns confidence and gaze_direction_x/y/z where the tracker gives them), RecordedEye,
// SampleCoordinateSystem "gaze-on-screen", SampleCoordinateUnits "pixel" and the screen
// (ScreenResolution in pixels, ScreenSize and ScreenDistance in metres). Beside it
// `…_physioevents.tsv.gz` (+ .json: Columns, OnsetSource "timestamp") holds the tracker's own
// events — fixations, blinks — and the recording blocks' starts (message START). The task's
// `…_events.tsv` carries the StimulusPresentation (the screen) BIDS asks of gaze-on-screen data.
// Samples the tracker lost (or that it, or its confidence, marks invalid) are written n/a.
#pragma once

#include "foveal/gaze/detect.h"
#include "foveal/gaze/recording.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace foveal {

// A path naming a BIDS physio file (…_physio.tsv.gz or …_physio.tsv).
bool is_bids_physio(const std::string& path);

// Read a BIDS eye-tracking recording with its sidecar (and physioevents, where present). Throws
// Error naming the file and the key or line: a sidecar without SamplingFrequency or Columns,
// columns that do not match the TSV, a physio file that is not PhysioType "eyetrack".
Recording read_bids_physio(const std::string& path, const ReadOptions& options = {});

// The same from contents already read (what the reader and the fuzz target call): the physio TSV
// (decompressed), its sidecar, and where the files are (for messages) with the physioevents and
// the task events' StimulusPresentation where there are any.
struct BidsFiles {
  std::string physio, sidecar;                          // names, for errors
  std::string events_name, events_sidecar, events_tsv;  // the physioevents (empty name: none)
  nlohmann::json events_json;                           // its sidecar
  nlohmann::json screen;                                // the task events' StimulusPresentation (null: none)
};
Recording parse_bids_physio(const std::string& tsv, const nlohmann::json& sidecar, const BidsFiles& files, const ReadOptions& options = {});

// Who and what a recording is in a dataset.
struct BidsEntities {
  std::string subject, session, task, run;  // session and run optional (empty)
};
// The entities' file stem: sub-S[_ses-X]_task-T[_run-N]_recording-eye1; throws Error naming the
// entity (labels are alphanumeric; run a positive integer).
std::string bids_stem(const BidsEntities& entities);
// The folder of a subject's (session's) eye-tracking files, relative to the dataset: sub-S[/ses-X]/beh.
std::string bids_folder(const BidsEntities& entities);

// Write `recording` into the dataset at `root` (created, with dataset_description.json and a
// README, where absent): the physio file and sidecar, the physioevents and the task's events
// with the screen. `screen_cm` is the display (width, height, viewing distance). Every file is
// written whole or not at all; an existing recording of the same entities is refused. Returns the
// physio file's path.
std::string write_bids_recording(const Recording& recording, const BidsEntities& entities, const std::string& root,
                                 const glm::dvec3& screen_cm);

// The events a detector found, as a derivative of that dataset: derivatives/foveal/sub-S/…/
// STEM_desc-foveal_physioevents.tsv.gz (onset in the recording's timestamps, duration, trial_type,
// amplitude, peak velocity, start/end in degrees) with a sidecar naming the detector and its
// parameters (`parameters`). Returns its path.
std::string write_bids_events(const EventDetection& detection, const BidsEntities& entities, const std::string& root,
                              const nlohmann::json& parameters);

}  // namespace foveal
