// foveal/io/video.h — frame sequences to video files with the ffmpeg program.
#pragma once

#include <string>

namespace foveal {

// Encode PNG frames named by a printf pattern (e.g. "out/frame_%05d.png", numbered from 0) into a
// video at `fps`. H.264 (yuv420p, CRF 18) for .mp4/.mkv/.mov, VP9 for .webm, else ffmpeg's
// choice for the extension. Throws Error when ffmpeg is missing or fails (with its last message).
void encode_video(const std::string& frame_pattern, double fps, const std::string& output);
// Decode every frame of a video to PNGs named by a printf pattern (numbered from 0); returns the
// video's frame rate. Throws Error naming the file when ffmpeg/ffprobe are missing or fail.
double decode_video(const std::string& input, const std::string& frame_pattern);

}  // namespace foveal
