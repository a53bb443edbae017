// .dof scene files: a shot as a small, versioned JSON document.
//
//   {
//     "version": 1,
//     "inputs": ["layers.exr"],
//     "scene":    { "frames": "1-24", "view": "left", "layer": "", "layers": 0 },
//     "camera":   { "focal": 85, "fstop": 1.4, "focus": { "1": 1.25, "24": 3.0 },
//                   "sensor": 36, "lens": "thin", "max_blur": 512 },
//     "aperture": { "shape": "disc" },
//     "color":    { "config": "", "input": "", "output": "" },
//     "output":   { "kind": "image", "type": "half", "compression": "zip",
//                   "crop": false }
//   }
//
// Every key but "version" and "inputs" is optional; shot_settings() lists
// them. Paths (inputs, masks, PSF images, configs) are relative to the
// .dof file.
#pragma once

#include <string>

#include <defocus/shot/shot.h>

namespace defocus {

/// The version of the .dof format this library writes; it reads this one
/// and older.
constexpr int shot_file_version = 1;

/// How deep .dof files may nest: a .dof whose inputs (or depth, mask or
/// PSF image) are .dof files, whose own are, ...
constexpr int max_shot_file_nesting = 8;

/// Reads a .dof file into `shot`, over its current values. False with
/// `error` a one-line message naming the file, the key and the problem:
/// bad JSON, a key given twice, an unknown key, a wrong type, a value out
/// of range, a missing file. The .dof files it names (as inputs, depth,
/// mask or PSF image) are read too, and theirs, by file identity: a file
/// that reaches itself is an error ("a.dof: refers to itself through
/// b.dof"), as is nesting deeper than max_shot_file_nesting.
bool load_shot(const std::string& filename, Shot& shot, std::string& error);

/// The same from text, with relative paths resolved against `directory`;
/// `source` names it in errors.
bool parse_shot(const std::string& text, const std::string& directory,
                const std::string& source, Shot& shot, std::string& error);

/// The .dof text of a shot whose paths are made relative to `directory`
/// where they lie beneath it.
std::string shot_to_json(const Shot& shot, const std::string& directory);

/// Writes a shot as a .dof file, atomically.
bool save_shot(const Shot& shot, const std::string& filename, std::string& error);

}  // namespace defocus
