// Keyframed settings: a value, or values at frames interpolated between
// them, as in "1001:3.0,1040:1.2,1100:1.2".
#pragma once

#include <array>
#include <string>
#include <vector>

namespace defocus {

/// How a setting moves between two keys.
enum class Interpolation {
    Linear,
    /// Linear in 1/value. A focus distance moved this way moves the CoC at
    /// an even rate (the CoC is linear in 1/z_f), and so does an f-number
    /// (the aperture diameter is f/N).
    Reciprocal,
};

/// A setting of one or two numbers (a pixel position) over frames: either
/// a constant or keys at integer frames. Before the first key and after
/// the last, the end keys hold.
class Keyframes {
public:
    using Value = std::array<double, 2>;
    struct Key {
        int frame = 0;
        Value value {};
    };

    Keyframes() = default;
    /// A constant single number.
    explicit Keyframes(double constant);

    /// Parses "V" (or "X,Y" when `arity` is 2) as a constant, or keys
    /// "F:V,F:V,..." (or "F:X,Y,F:X,Y,...") at strictly increasing frames.
    /// Every number must be finite and within [lo, hi]. On failure sets
    /// `error` to a message naming `option`, and the form with `value` (as
    /// the option's help writes it: "THRESHOLD,GAIN"; "" = "V" or "X,Y"),
    /// and returns false.
    static bool parse(const std::string& option, const std::string& text, int arity,
                      double lo, double hi, Keyframes& result, std::string& error,
                      const std::string& value = "");

    bool empty() const { return m_keys.empty(); }
    /// True when the keys give more than one frame.
    bool animated() const { return !m_constant && !m_keys.empty(); }
    const std::vector<Key>& keys() const { return m_keys; }

    /// The value at `frame`; must not be empty.
    Value at(double frame, Interpolation interpolation) const;

    /// The text parse() reads, e.g. "2.5" or "1:1.25,24:3".
    std::string to_string() const;

private:
    std::vector<Key> m_keys;
    int m_arity     = 1;
    bool m_constant = true;
};

}  // namespace defocus
