#include <defocus/shot/options.h>

#include <OpenImageIO/strutil.h>

#include "util/parse_name.h"

namespace defocus {

bool parse_edge_mode(const std::string& name, EdgeMode& mode)
{
    return parse_name(name, { EdgeMode::Auto, EdgeMode::Extend, EdgeMode::Black },
                      edge_mode_name, mode);
}

const char* edge_mode_name(EdgeMode mode)
{
    switch (mode) {
    case EdgeMode::Auto: return "auto";
    case EdgeMode::Extend: return "extend";
    case EdgeMode::Black: return "black";
    }
    return "?";
}

bool parse_missing_frames(const std::string& name, MissingFrames& missing)
{
    return parse_name(name, { MissingFrames::Error, MissingFrames::Skip, MissingFrames::Hold },
                      missing_frames_name, missing);
}

const char* missing_frames_name(MissingFrames missing)
{
    switch (missing) {
    case MissingFrames::Error: return "error";
    case MissingFrames::Skip: return "skip";
    case MissingFrames::Hold: return "hold";
    }
    return "?";
}

bool parse_output_window(const std::string& name, OutputWindow& window)
{
    return parse_name(name, { OutputWindow::Input, OutputWindow::Display, OutputWindow::Grown },
                      output_window_name, window);
}

bool parse_aov(const std::string& name, Aov& aov)
{
    return parse_name(name, { Aov::None, Aov::Confidence, Aov::Coc }, aov_name, aov);
}

const char* aov_name(Aov aov)
{
    switch (aov) {
    case Aov::Confidence: return "confidence";
    case Aov::Coc: return "coc";
    default: return "none";
    }
}

const std::vector<std::string>& aov_channel_names(Aov aov)
{
    // In OpenEXR's order (it sorts a file's channels by name), so that an
    // image and its file agree.
    static const std::vector<std::string> none, coc = { "coc" },
                                                confidence = { "confidence",
                                                               "confidence.continued",
                                                               "confidence.lines",
                                                               "confidence.patterns",
                                                               "confidence.smooth" };
    return aov == Aov::Confidence ? confidence : aov == Aov::Coc ? coc : none;
}

const char* output_window_name(OutputWindow window)
{
    switch (window) {
    case OutputWindow::Input: return "input";
    case OutputWindow::Display: return "display";
    case OutputWindow::Grown: return "grown";
    }
    return "?";
}

const char* data_kind_name(DataKind kind)
{
    switch (kind) {
    case DataKind::Id: return "id";
    case DataKind::Dominant: return "dominant";
    case DataKind::Average: return "average";
    }
    return "?";
}

bool parse_data_channels(const std::string& label, const std::string& setting,
                         std::vector<DataChannelEntry>& entries, std::string& error)
{
    using OIIO::Strutil::fmt::format;
    entries.clear();
    if (setting == "none")
        return true;
    for (std::string item : OIIO::Strutil::splits(setting, ",")) {
        item = OIIO::Strutil::strip(item);
        DataChannelEntry entry;
        entry.automatic = item == "auto";
        const size_t colon = item.rfind(':');
        if (!entry.automatic)
            entry.name = item.substr(0, colon);
        if (!entry.automatic && colon != std::string::npos
            && !parse_name(item.substr(colon + 1),
                           { DataKind::Id, DataKind::Dominant, DataKind::Average },
                           data_kind_name, entry.kind)) {
            error = format("{}: unknown kind '{}' for channel {} (choose id, dominant or "
                           "average)", label, item.substr(colon + 1), entry.name);
            return false;
        }
        if (!entry.automatic && entry.name.empty()) {
            error = format("{}: an empty channel name in '{}' (give none, auto, or channel "
                           "names, each with an optional :id, :dominant or :average)",
                           label, setting);
            return false;
        }
        entries.push_back(entry);
    }
    return true;
}

}  // namespace defocus
