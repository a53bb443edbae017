#include <defocus/io/file_stamps.h>

namespace defocus {

std::vector<FileStamp> stamp_files(const std::vector<std::string>& files)
{
    std::vector<FileStamp> found;
    for (const std::string& file : files) {
        struct stat st {};
        if (::stat(file.c_str(), &st) == 0)
            found.push_back({ file, st.st_dev, st.st_ino, st.st_size, st.st_mtim });
        else
            found.push_back({ file });
    }
    return found;
}

std::string first_changed(const std::vector<FileStamp>& stamps)
{
    for (const FileStamp& then : stamps) {
        const FileStamp now = stamp_files({ then.file }).front();
        if (then.device != now.device || then.inode != now.inode || then.size != now.size
            || then.modified.tv_sec != now.modified.tv_sec
            || then.modified.tv_nsec != now.modified.tv_nsec)
            return then.file;
    }
    return "";
}

}  // namespace defocus
