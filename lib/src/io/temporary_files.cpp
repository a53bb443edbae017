#include "io/temporary_files.h"

#include <defocus/io/image_output.h>

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

namespace Filesystem = OIIO::Filesystem;
namespace Strutil = OIIO::Strutil;

namespace {

/// The temporary files being written, for the signal handler: fixed slots
/// of plain characters, since a handler may neither allocate nor lock.
struct Slot {
    std::atomic<int> state { 0 };  ///< 0 free, 1 being filled, 2 in use
    char path[PATH_MAX];
};
constexpr int slot_count = 64;
Slot slots[slot_count];

int take_slot(const std::string& path)
{
    if (path.size() >= PATH_MAX)
        return -1;
    for (int i = 0; i < slot_count; ++i) {
        int free = 0;
        if (slots[i].state.compare_exchange_strong(free, 1)) {
            std::memcpy(slots[i].path, path.c_str(), path.size() + 1);
            slots[i].state.store(2);
            return i;
        }
    }
    return -1;  // more files in flight than slots: not removed on a signal
}

void handle_interrupt(int signal_number)
{
    for (Slot& slot : slots)
        if (slot.state.load() == 2)
            unlink(slot.path);
    ::signal(signal_number, SIG_DFL);
    raise(signal_number);
}

std::string host_name()
{
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) != 0 || !name[0])
        return "host";
    // A dot would make the name ambiguous.
    return Strutil::replace(name, ".", "_", true);
}

/// Removes the temporary files that processes of this host which no
/// longer run left beside `target` (killed by SIGKILL, or the machine
/// lost power).
void remove_leftovers(const std::string& target, const std::string& host)
{
    const std::string dir = Filesystem::parent_path(target);
    const std::string prefix = "." + Filesystem::filename(target) + "." + host + ".";
    std::vector<std::string> entries;
    if (!Filesystem::get_directory_entries(dir.empty() ? "." : dir, entries))
        return;
    for (const std::string& entry : entries) {
        const std::string name = Filesystem::filename(entry);
        if (!Strutil::starts_with(name, prefix))
            continue;
        OIIO::string_view rest(name);
        rest.remove_prefix(prefix.size());
        int pid = 0;
        if (!Strutil::parse_int(rest, pid) || !Strutil::starts_with(rest, ".tmp") || pid <= 0
            || pid == getpid())
            continue;
        if (kill(pid, 0) != 0 && errno == ESRCH)
            Filesystem::remove(entry);
    }
}

}  // namespace

TemporaryFile::TemporaryFile(const std::string& target)
    : m_target(target)
{
    const std::string host = host_name();
    remove_leftovers(target, host);
    const std::string dir = Filesystem::parent_path(target);
    const std::string name = Strutil::fmt::format(".{}.{}.{}.tmp{}", Filesystem::filename(target),
                                                  host, getpid(), Filesystem::extension(target));
    m_path = dir.empty() ? name : dir + "/" + name;
    m_slot = take_slot(m_path);
}

TemporaryFile::~TemporaryFile()
{
    if (!m_committed)
        Filesystem::remove(m_path);
    if (m_slot >= 0)
        slots[m_slot].state.store(0);
}

bool TemporaryFile::commit(std::string& error)
{
    std::string rename_error;
    if (Filesystem::rename(m_path, m_target, rename_error)) {
        m_committed = true;
        return true;
    }
    error = Strutil::fmt::format("{}: {}", m_target, rename_error);
    return false;
}

void remove_temporaries_on_interrupt()
{
    struct sigaction action = {};
    action.sa_handler = handle_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

}  // namespace defocus
