#include "io/temporary_files.h"

#include <defocus/io/image_output.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
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
    char folder[PATH_MAX];  ///< "" unless the file is in a folder of its own
};
constexpr int slot_count = 64;
Slot slots[slot_count];

int take_slot(const std::string& path, const std::string& folder)
{
    if (path.size() >= PATH_MAX || folder.size() >= PATH_MAX)
        return -1;
    for (int i = 0; i < slot_count; ++i) {
        int free = 0;
        if (slots[i].state.compare_exchange_strong(free, 1)) {
            std::memcpy(slots[i].path, path.c_str(), path.size() + 1);
            std::memcpy(slots[i].folder, folder.c_str(), folder.size() + 1);
            slots[i].state.store(2);
            return i;
        }
    }
    return -1;  // more files in flight than slots: not removed on a signal
}

/// "PROGRAM: " for the handler's last line, set before it is installed.
char program_prefix[64];

void write_to_stderr(const char* text)
{
    // write(2) is safe in a signal handler; what it cannot write is lost.
    const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
    (void)ignored;
}

void handle_interrupt(int signal_number)
{
    for (Slot& slot : slots)
        if (slot.state.load() == 2) {
            unlink(slot.path);
            if (slot.folder[0])
                rmdir(slot.folder);
        }
    // A farm's log ends with why the task ended, not mid-line.
    write_to_stderr(program_prefix);
    write_to_stderr(signal_number == SIGINT    ? "stopped by signal INT"
                    : signal_number == SIGTERM ? "stopped by signal TERM"
                    : signal_number == SIGHUP  ? "stopped by signal HUP"
                                               : "stopped by signal PIPE");
    write_to_stderr(": outputs not finished were not written\n");
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

/// Ten random characters: with the host and the process, a name nobody can
/// guess in advance.
std::string random_part()
{
    static const char letters[] = "abcdefghijklmnopqrstuvwxyz0123456789";
    unsigned char bytes[10] = {};
    if (getrandom(bytes, sizeof bytes, 0) != ssize_t(sizeof bytes)) {
        // No entropy source: the clock and a counter still make the name
        // new; O_EXCL keeps it safe.
        static std::atomic<uint64_t> counter { 0 };
        uint64_t seed = uint64_t(std::chrono::steady_clock::now().time_since_epoch().count())
                        ^ (++counter * 0x9e3779b97f4a7c15ull);
        for (unsigned char& b : bytes) {
            b = uint8_t(seed);
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        }
    }
    std::string part;
    for (unsigned char b : bytes)
        part += letters[b % (sizeof letters - 1)];
    return part;
}

/// Removes the temporary files and folders that processes of this host
/// which no longer run left beside `target` (killed by SIGKILL, or the
/// machine lost power).
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
        if (!Strutil::parse_int(rest, pid) || !Strutil::starts_with(rest, ".")
            || !Strutil::contains(rest, ".tmp") || pid <= 0 || pid == getpid())
            continue;
        std::string ignored;
        if (kill(pid, 0) != 0 && errno == ESRCH)
            Filesystem::remove_all(entry, ignored);  // a link itself, never what it names
    }
}

std::string system_error()
{
    return std::strerror(errno);
}

/// Why `target`, which is there as `existing` says, is not replaced; ""
/// when it may be.
std::string problem_replacing(const std::string& target, const struct stat& existing)
{
    if (S_ISDIR(existing.st_mode))
        return "is a folder";
    if (!S_ISREG(existing.st_mode))
        return S_ISFIFO(existing.st_mode)  ? "is a FIFO, not a regular file: not replaced"
               : S_ISSOCK(existing.st_mode) ? "is a socket, not a regular file: not replaced"
                                            : "is a device, not a regular file: not replaced";
    if (::access(target.c_str(), W_OK) != 0)
        return "is read-only for you: not replaced (make it writable, or remove it)";
    return "";
}

}  // namespace

std::string replace_problem(const std::string& target)
{
    struct stat existing;
    return ::stat(target.c_str(), &existing) == 0 ? problem_replacing(target, existing) : "";
}

TemporaryFile::TemporaryFile(const std::string& target, Kind kind)
    : m_target(target)
{
    const std::string host = host_name();
    remove_leftovers(target, host);
    const std::string dir = Filesystem::parent_path(target);
    const std::string name = Filesystem::filename(target);
    for (int attempt = 0; attempt < 100; ++attempt) {
        const std::string stem = Strutil::fmt::format(".{}.{}.{}.{}.tmp", name, host, getpid(),
                                                      random_part());
        const std::string here = dir.empty() ? stem : dir + "/" + stem;
        if (kind == Kind::File) {
            m_fd = ::open((here + Filesystem::extension(target)).c_str(),
                          O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
            if (m_fd >= 0) {
                m_path = here + Filesystem::extension(target);
                break;
            }
        } else if (::mkdir(here.c_str(), 0700) == 0) {
            m_folder = here;
            m_path   = here + "/" + name;
            break;
        }
        if (errno != EEXIST) {
            m_error = Strutil::fmt::format("{}: cannot write: {}", target, system_error());
            return;
        }
    }
    if (m_path.empty()) {
        m_error = target + ": cannot write: no new temporary name beside it";
        return;
    }
    m_slot = take_slot(m_path, m_folder);
}

TemporaryFile::~TemporaryFile()
{
    if (m_fd >= 0)
        ::close(m_fd);
    if (!m_committed && !m_path.empty())
        ::unlink(m_path.c_str());
    if (!m_folder.empty())
        ::rmdir(m_folder.c_str());
    if (m_slot >= 0)
        slots[m_slot].state.store(0);
}

bool TemporaryFile::write(const void* data, size_t size, std::string& why)
{
    const char* bytes = static_cast<const char*>(data);
    for (size_t done = 0; done < size;) {
        const ssize_t n = ::write(m_fd, bytes + done, size - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            why = n < 0 ? system_error() : std::strerror(ENOSPC);
            return false;
        }
        done += size_t(n);
    }
    return true;
}

bool TemporaryFile::commit(std::string& error)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: cannot write: {}", m_target, why);
        return false;
    };
    // What the file system still holds in memory reaches the disk now, or
    // fails now: after a rename it could be lost with the old file gone.
    const int fd = m_fd >= 0 ? m_fd : ::open(m_path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    m_fd = -1;
    if (fd < 0)
        return fail(system_error());
    struct stat existing;
    const bool replacing = ::stat(m_target.c_str(), &existing) == 0;
    if (const std::string problem = replacing ? problem_replacing(m_target, existing) : "";
        !problem.empty()) {
        ::close(fd);
        error = m_target + ": " + problem;
        return false;
    }
    // A file replaced keeps its permissions, and its owner where we may
    // give it (root), as cp's would.
    if (replacing
        && ((geteuid() == 0 && ::fchown(fd, existing.st_uid, existing.st_gid) != 0)
            || ::fchmod(fd, existing.st_mode & 07777) != 0)) {
        const std::string why = system_error();
        ::close(fd);
        return fail(why);
    }
    const bool synced = ::fsync(fd) == 0;
    const std::string sync_error = synced ? "" : system_error();
    if (::close(fd) != 0 || !synced)
        return fail(synced ? system_error() : sync_error);
    if (::rename(m_path.c_str(), m_target.c_str()) != 0)
        return fail(system_error());
    m_committed = true;
    // The rename itself, to the disk (best effort: not every file system
    // can sync a folder).
    const std::string dir = Filesystem::parent_path(m_target);
    const int folder = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folder >= 0) {
        ::fsync(folder);
        ::close(folder);
    }
    return true;
}

void remove_temporaries_on_interrupt(const char* program)
{
    const std::string prefix = std::string(program) + ": ";
    std::snprintf(program_prefix, sizeof program_prefix, "%s", prefix.c_str());
    struct sigaction action = {};
    action.sa_handler = handle_interrupt;
    sigemptyset(&action.sa_mask);
    // A terminal closing, a reader of the output gone (| head), Ctrl-C, a
    // farm's kill: the temporaries go, and the process ends by the signal.
    for (int signal_number : { SIGINT, SIGTERM, SIGHUP, SIGPIPE })
        sigaction(signal_number, &action, nullptr);
    // Past the file size limit (ulimit -f) a write fails with EFBIG and is
    // reported like a full disk, instead of the process being killed.
    ::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace defocus
