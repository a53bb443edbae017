#include <defocus/shot/keyframes.h>

#include <algorithm>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>

namespace defocus {

using OIIO::Strutil::fmt::format;


Keyframes::Keyframes(double constant)
    : m_keys { Key { 0, { constant, 0.0 } } }
{
}

bool Keyframes::parse(const std::string& option, const std::string& text, int arity,
                      double lo, double hi, Keyframes& result, std::string& error,
                      const std::string& value)
{
    const std::vector<std::string> tokens = OIIO::Strutil::splits(text, ",");
    const bool keyed = OIIO::Strutil::contains(text, ":");
    const std::string v = !value.empty() ? value : arity == 1 ? "V" : "X,Y";
    const std::string form = format("{0} or F:{0},F:{0},...", v);
    if (tokens.empty() || tokens.size() % arity != 0) {
        error = format("{}: '{}' is not {}", option, text, form);
        return false;
    }
    Keyframes k;
    k.m_arity    = arity;
    k.m_constant = !keyed;
    if (!keyed && tokens.size() != size_t(arity)) {
        error = format("{}: '{}' is not {}", option, text, form);
        return false;
    }
    for (size_t t = 0; t < tokens.size(); t += arity) {
        Key key;
        std::string first = tokens[t];
        if (keyed) {
            const size_t colon = first.find(':');
            if (colon == std::string::npos) {
                error = format("{}: '{}' is not {}", option, text, form);
                return false;
            }
            if (!parse_whole_number(option + " frame", first.substr(0, colon), -1e9,
                                    1e9, key.frame, error))
                return false;
            first = first.substr(colon + 1);
            if (!k.m_keys.empty() && key.frame <= k.m_keys.back().frame) {
                error = format("{}: the frames of the keys must increase ({} after {})",
                               option, key.frame, k.m_keys.back().frame);
                return false;
            }
        }
        for (int c = 0; c < arity; ++c)
            if (!parse_number(option, c == 0 ? first : tokens[t + c], lo, hi,
                             key.value[c], error))
                return false;
        k.m_keys.push_back(key);
    }
    result = std::move(k);
    return true;
}

Keyframes::Value Keyframes::at(double frame, Interpolation interpolation) const
{
    if (frame <= m_keys.front().frame || m_constant)
        return m_keys.front().value;
    if (frame >= m_keys.back().frame)
        return m_keys.back().value;
    // The first key at or after the frame; keys are in increasing frames.
    const auto after = std::lower_bound(m_keys.begin(), m_keys.end(), frame,
                                        [](const Key& key, double f) { return key.frame < f; });
    const Key& a   = *(after - 1);
    const Key& b   = *after;
    const double t = (frame - a.frame) / double(b.frame - a.frame);
    Value v {};
    for (int c = 0; c < m_arity; ++c) {
        if (interpolation == Interpolation::Reciprocal)
            v[c] = 1.0 / ((1.0 - t) / a.value[c] + t / b.value[c]);
        else
            v[c] = (1.0 - t) * a.value[c] + t * b.value[c];
    }
    return v;
}

std::string Keyframes::to_string() const
{
    std::vector<std::string> parts;
    for (const Key& key : m_keys) {
        std::string values = format("{}", key.value[0]);
        if (m_arity == 2)
            values += format(",{}", key.value[1]);
        parts.push_back(m_constant ? values : format("{}:{}", key.frame, values));
    }
    return OIIO::Strutil::join(parts, ",");
}

}  // namespace defocus
