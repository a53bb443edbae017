#include <defocus/stage_timeline.h>

#include <algorithm>
#include <utility>
#include <vector>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

void StageTimeline::close(int frame, Clock::time_point now)
{
    for (Stay& s : m_stays)
        if (s.frame == frame && s.open) {
            s.end = now;
            s.open = false;
        }
}

std::string stage_of(const std::string& name)
{
    const size_t space = name.rfind(' ');
    if (space == std::string::npos)
        return name;
    const std::string count = name.substr(space + 1);
    const size_t slash = count.find('/');
    const bool steps = slash != std::string::npos && slash > 0 && slash + 1 < count.size()
                       && count.find_first_not_of("0123456789/") == std::string::npos;
    return steps ? name.substr(0, space) : name;
}

void StageTimeline::enter(int frame, const std::string& name)
{
    const std::string stage = stage_of(name);
    std::lock_guard<std::mutex> lock(m_mutex);
    for (const Stay& s : m_stays)
        if (s.frame == frame && s.open && s.stage == stage)
            return;
    const Clock::time_point now = Clock::now();
    close(frame, now);
    m_stays.push_back({ frame, stage, now, now, true });
}

std::string StageTimeline::finish(int frame)
{
    std::lock_guard<std::mutex> lock(m_mutex);
    const Clock::time_point now = Clock::now();
    close(frame, now);
    auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
    std::string report;
    bool beside_any = false;
    for (const Stay& own : m_stays) {
        // Stages of a few milliseconds (colour without a conversion) say nothing.
        if (own.frame != frame || own.end - own.begin < std::chrono::milliseconds(5))
            continue;
        // The parts of the stage during which others ran, merged.
        std::vector<std::pair<Clock::time_point, Clock::time_point>> beside;
        std::vector<std::string> met;
        for (const Stay& other : m_stays) {
            const Clock::time_point end = other.open ? now : other.end;
            const Clock::time_point b = std::max(own.begin, other.begin),
                                    e = std::min(own.end, end);
            if (other.frame == frame || e <= b)
                continue;
            beside.emplace_back(b, e);
            const std::string name = format("{} {}", other.frame, other.stage);
            if (std::find(met.begin(), met.end(), name) == met.end())
                met.push_back(name);
        }
        std::sort(beside.begin(), beside.end());
        Clock::duration overlapped {};
        Clock::time_point reached = own.begin;
        for (const auto& [b, e] : beside) {
            if (e > reached)
                overlapped += e - std::max(b, reached);
            reached = std::max(reached, e);
        }
        beside_any |= !met.empty();
        report += format("{}{} {:.2f} s", report.empty() ? "" : ", ", own.stage,
                         seconds(own.end - own.begin));
        if (!met.empty())
            report += format(" ({:.2f} s beside {})", seconds(overlapped),
                             OIIO::Strutil::join(met, ", "));
    }
    // What no frame still in flight can meet any more: every stay that
    // ended before the earliest stay of a frame in flight began (frames
    // yet to start begin now or later).
    Clock::time_point earliest = now;
    for (const Stay& s : m_stays)
        if (s.open)
            for (const Stay& first : m_stays)
                if (first.frame == s.frame) {
                    earliest = std::min(earliest, first.begin);
                    break;
                }
    m_stays.erase(std::remove_if(m_stays.begin(), m_stays.end(),
                                 [&](const Stay& s) {
                                     return !s.open && s.end <= earliest;
                                 }),
                  m_stays.end());
    return beside_any ? report : std::string();
}

}  // namespace defocus
