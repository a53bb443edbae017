// Writing results without ever leaving a half-written file behind.
#pragma once

#include <functional>
#include <set>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/scene.h>

namespace defocus {

/// Writes a file atomically: `write` puts the complete file under the
/// temporary name it is given, beside `filename`, which is then renamed
/// over `filename`. Readers never see a partial file. On failure the
/// temporary is removed and `error` names the file and the problem.
bool write_atomic(const std::string& filename,
                  const std::function<bool(OIIO::ImageOutput& out,
                                           const std::string& temporary)>& write,
                  std::string& error);

/// Makes SIGINT and SIGTERM remove every temporary file being written,
/// say so on stderr ("PROGRAM: stopped by signal TERM: ..."), then end the
/// process by the same signal (a shell sees 130 or 143): an interrupted
/// run leaves its targets as they were, and a farm task's log says why it
/// ended. For programs to call at start, not for a library inside a host.
/// What SIGKILL leaves behind is removed by the next write of the same
/// target on the same host.
void remove_temporaries_on_interrupt(const char* program);

/// Whether `filename` can be written as an image, checked before any work
/// is done: its folder exists and is writable, a format writes its
/// extension, and `compression` ("" for the default) is one that format
/// knows; for a `deep` image, the format is OpenEXR and the compression one
/// of deep_compressions(); where `named_channels` names the settings that
/// add channels known by name ("" for none), the format keeps channel
/// names. Otherwise `error` names the file and the problem.
bool check_output(const std::string& filename, const std::string& compression,
                  std::string& error, bool deep = false,
                  const std::string& named_channels = "");

/// The compressions deep EXR files are written with.
const std::set<std::string>& deep_compressions();

/// The compression a deep result is written with: the one `given`
/// (checked by check_output()), else the input's when it is one of those,
/// else zips.
std::string deep_compression(const std::string& given, const std::string& inherited);

/// Whether the files a run writes leave every file it reads alone: false
/// when one of `written` is one of `read`, by file identity (device and
/// inode, so symbolic and hard links count), with `error` naming both
/// ("out.exr: would overwrite the input in.exr"). Empty names and files
/// that do not exist yet are skipped.
bool check_overwrites(const std::vector<std::string>& read,
                      const std::vector<std::string>& written, std::string& error);

/// Whether two names, existing or not, lead to the same file.
bool same_path(const std::string& a, const std::string& b);

/// True when `filename` is an image that defocus wrote with the settings
/// whose settings_hash() is `hash` (its defocus:settingsHash); else false
/// with `why` saying what is there instead ("does not exist", "was written
/// with other settings", ...).
bool written_with_settings(const std::string& filename, const std::string& hash,
                           std::string& why);

/// Writes a text file atomically, as write_atomic() does.
bool write_text_atomic(const std::string& filename, const std::string& text,
                       std::string& error);

/// Writes `image` to `filename` in the format its extension names, as
/// `type` (TypeUnknown: the image's own pixel type) with `compression`
/// ("" for the image's own or the format's default), atomically. A format
/// without a display window (PNG, JPEG) gets the display window's pixels.
/// A deep image keeps its own channel types; the last `float_channels`
/// channels (data: IDs are float bits) are written as float whatever
/// `type` is, where the format has a type per channel. `written`, where
/// given, is set to the type the format took.
bool write_image_atomic(const OIIO::ImageBuf& image, const std::string& filename,
                        OIIO::TypeDesc type, const std::string& compression,
                        std::string& error, int float_channels = 0,
                        OIIO::TypeDesc* written = nullptr);

/// Writes layers as a multi-part EXR, one part per layer named after it,
/// with float R,G,B,A,Z over its own data window, the display window and
/// metadata of `spec`: a file read_scene() takes back as the same layers.
bool write_layers_atomic(const std::vector<Layer>& layers, const OIIO::ImageSpec& spec,
                         const std::string& filename, std::string& error);

}  // namespace defocus
