#include <defocus/frame_scheduler.h>

#include <sys/resource.h>

#include <algorithm>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <OpenImageIO/strutil.h>
#include <OpenImageIO/sysutil.h>

namespace defocus {

namespace {

size_t peak_resident_bytes()
{
    struct rusage usage {};
    getrusage(RUSAGE_SELF, &usage);
    return size_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

}  // namespace

ScheduleResult run_frames(int count, int threads, size_t memory_limit, bool stop_on_error,
                          const FrameJob& job, const FrameSize& size)
{
    ScheduleResult result;
    if (count <= 0)
        return result;
    const int cores = threads > 0 ? threads : int(OIIO::Sysutil::hardware_concurrency());

    const size_t before = OIIO::Sysutil::memory_used(true);
    const double first_size = size ? size(0) : 0.0;
    result.run = 1;
    if (!job(0)) {
        result.failed.push_back(0);
        if (stop_on_error)
            return result;
    }
    if (count == 1)
        return result;
    const size_t peak = peak_resident_bytes();
    const size_t first_peak = std::max(peak > before ? peak - before : 0, size_t(64) << 20);
    auto expected = [&](int i) {
        const double declared = size && first_size > 0.0 ? size(i) : 0.0;
        if (declared <= 0.0)
            return first_peak;
        const double scaled = double(first_peak) * declared / first_size;
        return size_t(std::clamp(scaled, double(size_t(64) << 20), double(memory_limit) + 1.0));
    };

    int next = 1;
    size_t in_flight = 0;  ///< the expected peaks of the frames running
    bool stop = false;
    std::mutex mutex;
    std::condition_variable finished;
    auto work = [&] {
        for (;;) {
            int i = 0;
            {
                std::lock_guard<std::mutex> lock(mutex);
                if (stop || next >= count)
                    return;
                i = next++;
            }
            const size_t need = expected(i);  // reads headers: outside the lock
            {
                std::unique_lock<std::mutex> lock(mutex);
                finished.wait(lock, [&] {
                    return stop || in_flight == 0 || in_flight + need <= memory_limit;
                });
                if (stop)
                    return;
                in_flight += need;
            }
            const bool ok = job(i);
            {
                std::lock_guard<std::mutex> lock(mutex);
                in_flight -= need;
                ++result.run;
                if (!ok) {
                    result.failed.push_back(i);
                    stop = stop || stop_on_error;
                }
            }
            finished.notify_all();
        }
    };
    std::vector<std::thread> pool;
    for (int w = 0; w < std::min(cores, count - 1); ++w)
        pool.emplace_back(work);
    for (std::thread& t : pool)
        t.join();
    std::sort(result.failed.begin(), result.failed.end());
    return result;
}

std::string frames_written(const ScheduleResult& run, const std::vector<int>& frames,
                           int skipped)
{
    using OIIO::Strutil::fmt::format;
    std::string summary = format("{} of {} frames written", run.run - int(run.failed.size()),
                                 frames.size());
    if (skipped > 0)
        summary += format(" ({} more skipped: written with these settings)", skipped);
    std::vector<std::string> failed;
    for (int i : run.failed)
        failed.push_back(std::to_string(frames[i]));
    if (!failed.empty())
        summary += "; failed: " + OIIO::Strutil::join(failed, ",");
    if (run.run < int(frames.size()))
        summary += "; stopped at the first bad frame";
    return summary;
}

}  // namespace defocus
