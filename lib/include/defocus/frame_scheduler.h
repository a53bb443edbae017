// Running the frames of a sequence on all cores within the memory limit.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace defocus {

/// Renders one frame (by index); false when it failed.
using FrameJob = std::function<bool(int index)>;

/// How much a frame's input files declare (declared_bytes), in bytes,
/// from their headers, before the frame is read.
using FrameSize = std::function<double(int index)>;

struct ScheduleResult {
    std::vector<int> failed;  ///< indices, in order
    int run = 0;              ///< frames attempted
};

/// Runs frames 0..count-1 in order of starting. The first runs alone, on
/// the calling thread, and its peak memory is measured; then up to one
/// worker thread per core takes frame after frame. A frame is expected to
/// take the first one's peak, scaled by how much more its input files
/// declare (`size`, when given: a sequence whose later frames are larger),
/// and starts only while the frames in flight, itself included, are
/// expected to stay within `memory_limit` bytes, or when it would run
/// alone. One frame alone rarely fills the cores (checking, reading and
/// writing EXR are largely serial); frames side by side do. Every frame
/// uses all of the shared thread pool, so that no core idles while the
/// last frames finish. With `stop_on_error`, no frame starts after one has
/// failed.
ScheduleResult run_frames(int count, int threads, size_t memory_limit, bool stop_on_error,
                          const FrameJob& job, const FrameSize& size = {});

/// The line that closes a sequence: "98 of 100 frames written (3 more
/// skipped: written with these settings); failed: 1004,1010; stopped at
/// the first bad frame" (when asked to stop there), each part only when it
/// applies. The words suit every caller: the CLI and the Python module.
/// `frames` are the frame numbers `run` ran over, by index.
std::string frames_written(const ScheduleResult& run, const std::vector<int>& frames,
                           int skipped = 0);

}  // namespace defocus
