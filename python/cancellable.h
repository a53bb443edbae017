// Work that Ctrl-C cancels: it runs on a thread of its own with the GIL
// released, while the calling thread waits and checks Python's signals.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include <pybind11/pybind11.h>

#include <defocus/render_frame.h>

namespace defocus_python {

namespace py = pybind11;

/// Runs work(cancelled) on its own thread while this one, GIL released,
/// waits and checks Python's signals every 50 ms. A signal handler that
/// raises (Ctrl-C: KeyboardInterrupt) sets `cancelled`; its exception is
/// raised once the work has stopped, so that no file is half written.
template<typename Work>
void run_cancellable(Work&& work)
{
    std::atomic<bool> cancelled { false };
    std::exception_ptr failure;
    std::mutex mutex;
    std::condition_variable finished_cv;
    bool finished = false;
    std::thread worker([&] {
        try {
            work(cancelled);
        } catch (...) {
            failure = std::current_exception();
        }
        std::lock_guard<std::mutex> lock(mutex);
        finished = true;
        finished_cv.notify_all();
    });
    bool interrupted = false;
    for (;;) {
        {
            py::gil_scoped_release release;
            std::unique_lock<std::mutex> lock(mutex);
            if (finished_cv.wait_for(lock, std::chrono::milliseconds(50),
                                     [&] { return finished; }))
                break;
        }
        if (!interrupted && PyErr_CheckSignals() != 0) {
            interrupted = true;
            cancelled = true;
        }
    }
    worker.join();
    if (interrupted)
        throw py::error_already_set();
    if (failure)
        std::rethrow_exception(failure);
}

/// A stage callback that stops the render once cancelled.
inline defocus::StageCallback stop_when(const std::atomic<bool>& cancelled)
{
    return [&cancelled](const char*) { return !cancelled; };
}

}  // namespace defocus_python
