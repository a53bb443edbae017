// Internal: the temporary files results are written to before they are
// renamed over their targets, and what happens to them when a process is
// interrupted or killed.
#pragma once

#include <cstddef>
#include <string>

namespace defocus {

/// Why an existing `target` must not be replaced ("" when it may be, or
/// does not exist): it is not a regular file (a device, a FIFO, a folder),
/// or this user cannot write it, as cp would refuse.
std::string replace_problem(const std::string& target);

/// A new temporary file beside `target`, named after it, this host, this
/// process and a random part (".NAME.HOST.PID.RANDOM.tmp.EXT"), created
/// by this object alone (O_CREAT | O_EXCL | O_NOFOLLOW: nothing planted at
/// that name, a symbolic link above all, is ever opened or followed), with
/// the permissions a new file gets. It is listed for removal if the process
/// is interrupted (remove_temporaries_on_interrupt, image_output.h) and
/// removed on destruction unless committed. Creating one first removes
/// what killed processes of this host left beside the same target.
///
/// Writers that can only open a file by name (OpenImageIO's without an
/// IOProxy) get a private folder instead (InFolder): a new folder beside
/// the target that only this user may enter, holding the file under the
/// target's own name.
class TemporaryFile {
public:
    enum class Kind { File, InFolder };
    explicit TemporaryFile(const std::string& target, Kind kind = Kind::File);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

    /// False when the file (or folder) could not be created; then
    /// creation_error() says why, naming the target.
    bool created() const { return m_error.empty(); }
    const std::string& creation_error() const { return m_error; }

    /// The file's name, to write it by name (InFolder).
    const std::string& path() const { return m_path; }
    /// The open file (File), for writing, or -1.
    int descriptor() const { return m_fd; }

    /// Writes all of `size` bytes to the open file, every write checked;
    /// false with `why` the system's reason (a full disk, a size limit).
    bool write(const void* data, size_t size, std::string& why);

    /// Makes the complete file the target: its data is flushed to the disk
    /// (fsync) and it is renamed over the target, so that a crash or a full
    /// disk never leaves a truncated target in place of the old one; a file
    /// it replaces keeps its mode (and, for root, its owner). False with
    /// `error` naming the target when any step fails or replace_problem()
    /// has one; the target is then as it was.
    bool commit(std::string& error);

private:
    std::string m_target, m_path, m_folder, m_error;
    int m_fd = -1;
    int m_slot = -1;
    bool m_committed = false;
};

}  // namespace defocus
