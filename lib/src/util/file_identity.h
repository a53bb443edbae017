// Internal: which file a name leads to, whatever the name.
#pragma once

#include <sys/stat.h>

#include <optional>
#include <string>

namespace defocus {

/// A file as the system knows it: device and inode. Two names of one file
/// (a symbolic link, a hard link, "./x" and "x") have the same identity.
struct FileIdentity {
    dev_t device = 0;
    ino_t inode  = 0;

    /// The identity of the file `path` leads to (links followed), or none
    /// when there is no such file.
    static std::optional<FileIdentity> of(const std::string& path)
    {
        struct stat st {};
        if (::stat(path.c_str(), &st) != 0)
            return std::nullopt;
        return FileIdentity { st.st_dev, st.st_ino };
    }

    bool operator==(const FileIdentity& o) const
    {
        return device == o.device && inode == o.inode;
    }
    bool operator<(const FileIdentity& o) const
    {
        return device != o.device ? device < o.device : inode < o.inode;
    }
};

}  // namespace defocus
