// Internal: the temporary files results are written to before they are
// renamed over their targets, and what happens to them when a process is
// interrupted or killed.
#pragma once

#include <string>

namespace defocus {

/// A temporary file beside `target`, named after it, this host and this
/// process (".NAME.HOST.PID.tmp.EXT"), listed for removal if the process is
/// interrupted (remove_temporaries_on_interrupt, image_output.h) and removed on destruction
/// unless it was committed. Creating one first removes what killed
/// processes of this host left beside the same target.
class TemporaryFile {
public:
    explicit TemporaryFile(const std::string& target);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

    const std::string& path() const { return m_path; }

    /// Renames the complete file over the target; false with `error`
    /// naming the target when that fails (the file is then removed).
    bool commit(std::string& error);

private:
    std::string m_target, m_path;
    int m_slot;
    bool m_committed = false;
};

}  // namespace defocus
