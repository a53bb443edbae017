// Which of an input's channels are data, and how each is carried.
#include <defocus/composite/data_channels.h>

#include <algorithm>
#include <map>
#include <set>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// The last dot-separated component of `name`, and the one before it.
std::string component(const std::string& name, int from_end)
{
    std::vector<std::string> parts = Strutil::splits(name, ".");
    if (int(parts.size()) <= from_end)
        return {};
    return Strutil::lower(parts[parts.size() - 1 - from_end]);
}

bool is_id_name(const std::string& name)
{
    static const std::set<std::string> ids { "id", "objectid", "object_id", "materialid",
                                             "material_id", "indexob", "indexma" };
    return ids.count(component(name, 0)) > 0;
}

/// P, N, Position, Normal: a vector of the surface each pixel shows.
bool is_surface_vector(const std::string& name, bool& normal)
{
    const std::string set = component(name, 1);
    normal = set == "n" || set == "normal";
    return normal || set == "p" || set == "position";
}

/// The cryptomatte sets of `input`: those its metadata names
/// (cryptomatte/<key>/name), and channel sets named Crypto*NN.R..A (under
/// any prefix).
std::vector<CryptoSet> crypto_sets(const ImageSpec& input)
{
    std::set<std::string> declared;
    for (const ParamValue& p : input.extra_attribs) {
        const std::string key = p.name().string();
        if (Strutil::starts_with(key, "cryptomatte/") && Strutil::ends_with(key, "/name")
            && p.type() == TypeString)
            declared.insert(p.get_string());
    }
    // Set name -> rank quad number -> which of R,G,B,A it has.
    std::map<std::string, std::map<int, int>> quads;
    for (const std::string& channel : input.channelnames) {
        const size_t dot = channel.rfind('.');
        if (dot == std::string::npos || dot < 3 || dot + 2 != channel.size())
            continue;
        const size_t rgba = std::string("RGBA").find(channel[dot + 1]);
        const std::string digits = channel.substr(dot - 2, 2);
        const std::string set = channel.substr(0, dot - 2);
        // Blender prefixes the view layer: ViewLayer.CryptoObject00.R.
        const std::string last = set.substr(set.rfind('.') + 1);
        if (rgba == std::string::npos || !isdigit(digits[0]) || !isdigit(digits[1])
            || !(declared.count(set) || Strutil::istarts_with(last, "crypto")))
            continue;
        quads[set][Strutil::stoi(digits)] |= 1 << rgba;
    }
    std::vector<CryptoSet> sets;
    for (const auto& [name, numbers] : quads) {
        CryptoSet set { name, {} };
        for (int n = 0; numbers.count(n) && numbers.at(n) == 15; ++n)
            for (const char* c : { "R", "G", "B", "A" })
                set.channels.push_back(format("{}{:02d}.{}", name, n, c));
        if (!set.channels.empty())
            sets.push_back(std::move(set));
    }
    return sets;
}

}  // namespace

std::vector<std::string> DataPlan::input_channels() const
{
    std::vector<std::string> names;
    for (const DataChannel& c : channels)
        names.push_back(c.name);
    for (const CryptoSet& set : crypto)
        names.insert(names.end(), set.channels.begin(), set.channels.end());
    return names;
}

std::vector<std::string> DataPlan::output_channels() const
{
    std::vector<std::string> names;
    if (depth)
        names = { "Z", "ZFront" };
    const std::vector<std::string> read = input_channels();
    names.insert(names.end(), read.begin(), read.end());
    return names;
}

bool DataPlan::distinct_names(Aov aov, std::string& error) const
{
    std::map<std::string, std::string> owner
        = { { "R", "the colour" }, { "G", "the colour" }, { "B", "the colour" },
            { "A", "the colour" } };
    for (const std::string& name : aov_channel_names(aov))
        owner[name] = mention("aov", aov_name(aov));
    const std::vector<std::string> names = output_channels();
    for (size_t i = 0; i < names.size(); ++i) {
        // The depth's two channels come first.
        const std::string which = depth && i == 1 ? "the data channel Z's ZFront"
                                                  : "the data channel " + names[i];
        const auto [it, added] = owner.emplace(names[i], which);
        if (!added) {
            error = format("{} and {} would both be written as channel {}", which, it->second,
                           names[i]);
            return false;
        }
    }
    return true;
}

std::string DataPlan::summary() const
{
    std::vector<std::string> carried;
    if (depth)
        carried.push_back("Z (coverage-weighted) and ZFront (the front-most layer's)");
    for (const DataChannel& channel : channels)
        carried.push_back(format("{} ({})", channel.name, data_kind_name(channel.kind)));
    for (const CryptoSet& set : crypto)
        carried.push_back(format("{} (cryptomatte, {} ranks)", set.name, set.ranks()));
    return carried.empty() ? "" : "data channels carried: " + Strutil::join(carried, ", ");
}

bool plan_data_channels(const ImageSpec& input, const std::string& setting, DataPlan& plan,
                        std::string& error)
{
    plan = DataPlan();
    std::vector<DataChannelEntry> entries;
    if (!parse_data_channels(mention("data-channels", setting), setting, entries, error))
        return false;
    auto add = [&](const std::string& name, DataKind kind) {
        bool normal = false;
        const bool vector = is_surface_vector(name, normal);
        auto same = [&](const DataChannel& c) { return c.name == name; };
        auto it = std::find_if(plan.channels.begin(), plan.channels.end(), same);
        if (it == plan.channels.end())
            plan.channels.push_back({ name, kind, vector && normal && kind == DataKind::Dominant });
        else
            *it = { name, kind, vector && normal && kind == DataKind::Dominant };
    };
    for (const DataChannelEntry& entry : entries) {
        if (entry.automatic) {
            plan.depth = true;
            plan.crypto = crypto_sets(input);
            for (const std::string& name : input.channelnames) {
                bool normal = false;
                if (is_id_name(name))
                    add(name, DataKind::Id);
                else if (is_surface_vector(name, normal))
                    add(name, DataKind::Dominant);
            }
            continue;
        }
        if (entry.name == "Z") {
            plan.depth = true;
            continue;
        }
        if (input.channelindex(entry.name) < 0) {
            error = format("{}: the input has no channel {} (channels: {})",
                           mention("data-channels", setting), entry.name,
                           Strutil::join(input.channelnames, ","));
            return false;
        }
        add(entry.name, entry.kind);
    }
    // A channel of a cryptomatte set is carried with its set.
    const std::vector<std::string> crypto_channels = DataPlan { false, {}, plan.crypto }.input_channels();
    plan.channels.erase(std::remove_if(plan.channels.begin(), plan.channels.end(),
                                       [&](const DataChannel& c) {
                                           return std::count(crypto_channels.begin(),
                                                             crypto_channels.end(), c.name) > 0;
                                       }),
                        plan.channels.end());
    return true;
}

}  // namespace defocus
