#include "io/part_channels.h"

#include <set>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

std::string channel_name(const std::string& prefix, const std::string& channel)
{
    return prefix.empty() ? channel : prefix + "." + channel;
}

int first_channel(const ImageSpec& spec, const std::vector<std::string>& names)
{
    for (const std::string& n : names) {
        const int c = spec.channelindex(n);
        if (c >= 0)
            return c;
    }
    return -1;
}

Channels find_channels(const ImageSpec& spec, const std::string& layer,
                       std::string& error)
{
    std::vector<std::string> prefixes;
    if (!layer.empty()) {
        prefixes = { layer, layer + ".Combined" };
    } else {
        prefixes = { "" };
        std::set<std::string> seen;
        for (const std::string& n : spec.channelnames)
            if (Strutil::ends_with(n, ".R") && seen.insert(n).second)
                prefixes.push_back(n.substr(0, n.size() - 2));
    }
    Channels ch;
    std::vector<std::string> rgba_sets, rgb_sets;
    for (const std::string& p : prefixes) {
        const int c[4] = { spec.channelindex(channel_name(p, "R")),
                           spec.channelindex(channel_name(p, "G")),
                           spec.channelindex(channel_name(p, "B")),
                           spec.channelindex(channel_name(p, "A")) };
        if (c[0] < 0 || c[1] < 0 || c[2] < 0)
            continue;
        auto& sets = c[3] >= 0 ? rgba_sets : rgb_sets;
        sets.push_back(p);
        if (rgba_sets.size() + rgb_sets.size() == 1 || (c[3] >= 0 && rgba_sets.size() == 1)) {
            ch.prefix = p;
            std::copy(c, c + 4, ch.color);
        }
    }
    const auto& complete = rgba_sets.empty() ? rgb_sets : rgba_sets;
    if (complete.size() > 1 && !complete.front().empty())
        error = format("it holds several layers ({}): choose one with {}",
                       Strutil::join(complete, ", "), mention("layer", "NAME"));

    std::string view_layer = ch.prefix;
    if (Strutil::ends_with(view_layer, ".Combined"))
        view_layer.resize(view_layer.size() - 9);
    std::vector<std::string> depth_names;
    if (!layer.empty())
        depth_names = { channel_name(layer, "Z"), channel_name(layer, "Depth.Z") };
    if (!ch.prefix.empty())
        depth_names.push_back(channel_name(ch.prefix, "Z"));
    if (!view_layer.empty())
        depth_names.push_back(channel_name(view_layer, "Depth.Z"));
    for (const char* n : { "Z", "depth.Z", "Depth.Z" })
        depth_names.emplace_back(n);
    ch.depth = first_channel(spec, depth_names);
    return ch;
}

std::string missing_channel(const ImageSpec& spec, const std::string& layer)
{
    for (const char* c : { "R", "G", "B" })
        if (spec.channelindex(channel_name(layer, c)) < 0
            && spec.channelindex(channel_name(layer, std::string("Combined.") + c)) < 0)
            return channel_name(layer, c);
    return channel_name(layer, "Z");
}

}  // namespace defocus
