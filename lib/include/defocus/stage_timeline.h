// When each frame of a run is in each stage, to show how frames run side
// by side overlap (defocus -v).
#pragma once

#include <chrono>
#include <deque>
#include <mutex>
#include <string>

namespace defocus {

/// The stage a stage callback's `name` names: without the count of its
/// steps done that a long stage adds ("data channels 12/134").
std::string stage_of(const std::string& name);

/// The stages of the frames a run has in flight, as they enter them, from
/// any thread. Only what a frame still in flight can meet is kept, so a
/// long sequence holds a few dozen entries.
class StageTimeline {
public:
    /// Frame `frame` enters `stage` (leaving the stage it was in); the
    /// same stage further on (see stage_of) is no new stage.
    void enter(int frame, const std::string& stage);

    /// Frame `frame` is done: for each of its stages, how long it took and
    /// for how long other frames ran beside it, in which stages: "read
    /// 0.61 s (0.45 s beside 1002 render), render 1.05 s (1.05 s beside
    /// 1002 write, 1004 read)", stages of under 5 ms left out. Empty when
    /// no other frame ran beside it.
    std::string finish(int frame);

private:
    using Clock = std::chrono::steady_clock;
    struct Stay {
        int frame;
        std::string stage;
        Clock::time_point begin, end;
        bool open;
    };
    void close(int frame, Clock::time_point now);
    std::mutex m_mutex;
    std::deque<Stay> m_stays;  ///< by time of entering
};

}  // namespace defocus
