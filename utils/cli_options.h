// Command-line options shared by defocus and layerize. Most options set a
// shot setting (see shot.h) of the same name; they are applied in the
// order given, over the values of a .dof file when one is read.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>

#include <defocus/shot/shot.h>

namespace defocus {

/// ap.parse_args(), also taking "--option=value" for "--option value".
int parse_arguments(OIIO::ArgParse& ap, int argc, const char* argv[]);

/// A parse error, with the nearest option when it names an unknown one
/// ('Invalid option "--focsu": did you mean --focus?').
std::string unknown_option_hint(const OIIO::ArgParse& ap, const std::string& error);

/// The width of the terminal stdout goes to; $COLUMNS, else 80, when it
/// is not a terminal. (OIIO 2.4's Sysutil::terminal_columns() reads an
/// unset size then.)
int terminal_columns();

/// --help: the help, its long lines wrapped to the terminal's width (80
/// columns when stdout is not a terminal), and the parse stopped. For an
/// ArgParse made with add_help(false); OIIO 2.4 prints lines whole.
void add_help_option(OIIO::ArgParse& ap);

/// --version: prints "PROGRAM VERSION" and stops the parse, as --help does.
void add_version_option(OIIO::ArgParse& ap, const char* program);

/// The options given on a command line: those that set shot settings, and
/// others stored into strings, with the checks they share (an option given
/// twice, options that contradict each other or do not apply).
class ShotArguments {
public:
    /// An ArgParse action that stores the option's value into `into`.
    std::function<void(OIIO::cspan<const char*>)> store_into(std::string& into);

    /// Adds the options of the settings of `group` (see shot_settings()),
    /// under the group's heading when it has one.
    void add_options(OIIO::ArgParse& ap, OptionGroup group);
    /// --threads.
    void add_threads(OIIO::ArgParse& ap);

    /// Applies the options given to `shot`, in command-line order. Fails
    /// when an option was given twice with different values, two options
    /// set one setting differently (--crop and --grow), or an option does
    /// not apply to the shot (--blades without --aperture polygon).
    bool apply(Shot& shot, std::string& error) const;
    /// The worker threads asked for (0 = all cores).
    bool threads(int& threads, std::string& error) const;

private:
    struct Given {
        std::string option, setting, value;  ///< setting: "" for stored options
    };
    std::vector<Given> m_given;
    std::string m_threads = "0";
};

}  // namespace defocus
