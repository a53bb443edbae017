// Files as they were when a scene was opened: a file replaced or rewritten
// since gives pixels that what was reported from it (a spec handed to a
// host) does not describe.
#pragma once

#include <sys/stat.h>

#include <string>
#include <vector>

namespace defocus {

/// One file's identity, size and modification time (all zero, size -1,
/// when it does not exist).
struct FileStamp {
    std::string file;
    dev_t device = 0;
    ino_t inode = 0;
    off_t size = -1;
    struct timespec modified {};
};

/// Each of `files` as it is now.
std::vector<FileStamp> stamp_files(const std::vector<std::string>& files);

/// The first of `stamps` whose file is not as it was then, or "".
std::string first_changed(const std::vector<FileStamp>& stamps);

}  // namespace defocus
