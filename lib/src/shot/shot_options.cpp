#include <defocus/shot/shot_options.h>

namespace defocus {

namespace {

using G = OptionGroup;

/// Which frames.
std::vector<ShotOption> sequence_options()
{
    return {
        { G::Sequences, "--frames LIST", "frames",
          "Frames to render: 1001-1100, 1-99x2 (every other), 1,5,9-12 "
          "(default: the frames the input pattern finds on disk)" },
        { G::Sequences, "--missing-frames error|skip|hold", "missing-frames",
          "Frames whose input files are missing (a gap in the sequence on disk, or a "
          "frame of --frames): error refuses the shot, naming them; skip renders the "
          "others; hold renders each from the nearest earlier frame's inputs "
          "(default: error)" },
    };
}

/// Focus, lens and filmback, and the lens's effects.
std::vector<ShotOption> camera_options()
{
    return {
        { G::Camera, "--focus DIST", "focus",
          "Focus distance in metres, e.g. 3 or 1001:3,1040:1.2 (required, or --focus-at, "
          "unless the render's header records it)" },
        { G::Camera, "--focus-at X,Y", "focus-at",
          "Focus on what is seen at display-window pixel X,Y: the median depth of the "
          "front-most opaque surface over 5x5 pixels (--focus-at-radius); keyframes "
          "F:X,Y,F:X,Y..." },
        { G::Camera, "--focus-at-radius R", "focus-at-radius",
          "--focus-at takes the median over (2R+1)x(2R+1) pixels: 0 = the pixel alone, "
          "larger for noisy depth (default: 2, 5x5)" },
        { G::Camera, "--focus-tilt DEG,DEG", "focus-tilt",
          "Tilt the plane of focus (Scheimpflug, the tilt-shift look) about the "
          "horizontal and the vertical axis through the focus point: positive turns "
          "its top, and its right side, away from the camera; -80..80; keyframes "
          "F:A,B,F:A,B... (default: 0,0)" },
        { G::Camera, "--split-diopter %s:X0,Y0,X1,Y1:DIST", "split-diopter",
          "A split-field diopter: beyond the line through display-window pixels "
          "X0,Y0 and X1,Y1 (on its right, walking from the first to the second), "
          "focus at DIST, changing over 4 pixels across the line; DIST may be "
          "keyframes F:D,F:D..." },
        { G::Camera, "--focal MM", "focal", "Focal length in mm (default: 50)" },
        { G::Camera, "--fstop N", "fstop", "Aperture f-number (default: 2.8)" },
        { G::Camera, "--sensor MM", "sensor",
          "Horizontal filmback width in mm, spanning the display window (default: 36)" },
        { G::Camera, "--camera-from-file on|off", "camera-from-file",
          "Take the focus, f-number, focal length and filmback a render recorded in "
          "its header (OpenEXR focus/aperture/camera matrices, Unreal, Arnold, V-Ray) "
          "where no option or "
          ".dof gives them, frame by frame; -v says where each value came from "
          "(default: on)" },
        { G::Camera, "--lens MODEL", "lens",
          "thin: render cameras, no breathing (default); optical: Potmesil & Chakravarty" },
        { G::Camera, "--max-blur PX", "max-blur",
          "Largest CoC diameter in pixels; larger blur is clamped (default: 512)" },

        { G::Camera, "--axial-ca AMOUNT", "axial-ca",
          "Axial chromatic aberration: red and blue blur 1+AMOUNT times green's in "
          "front of the focus and 1-AMOUNT times behind it (purple and green bokeh "
          "rims as a fast lens; nothing in focus fringes), -0.5..0.5 (default: 0)" },
        { G::Camera, "--lateral-ca AMOUNT", "lateral-ca",
          "Lateral chromatic aberration: red magnified by 1+AMOUNT and blue by "
          "1-AMOUNT about the optical centre, in the spread, -0.05..0.05 (default: 0)" },
        { G::Camera, "--cateye AMOUNT", "cateye",
          "Optical vignetting: towards the edges the bokeh is clipped by a disc offset "
          "towards the optical centre; 1 = at the farthest corner the clip reaches the "
          "bokeh's centre; 0..1.5. Spreads every pixel on its own: time grows with the "
          "blur (default: 0)" },
        { G::Camera, "--optical-centre X,Y", "optical-centre",
          "Where the lens's axis meets the image, display-window pixels, for "
          "--lateral-ca and --cateye (default: the display window's centre)" },
    };
}

/// The bokeh's shape and how it is spread.
std::vector<ShotOption> aperture_options()
{
    return {
        { G::Aperture, "--aperture SHAPE", "aperture",
          "Bokeh shape: disc (default); polygon (an iris of --blades blades, its "
          "vertices on the CoC circle, as render cameras draw it); mask:FILE (the "
          "shape in an image, thresholded at half its peak, with the disc's area); "
          "box (a square of the disc's area: the fastest); tent and smooth (soft "
          "PSFs of the disc's spread, in constant time)" },
        { G::Aperture, "--blades N", "blades", "Polygon: number of blades, 3-16 (default: 6)" },
        { G::Aperture, "--rotation DEG", "rotation",
          "Polygon: rotation clockwise in the image, as Blender/Cycles' aperture "
          "rotation is given (the same number); 0 = a vertex pointing right "
          "(default: 0)" },
        { G::Aperture, "--roundness R", "roundness",
          "Polygon: 0 = straight blades, 1 = a disc (default: 0)" },
        { G::Aperture, "--aspect A", "aspect",
          "Anamorphic squeeze: < 1 narrows the bokeh horizontally (default: 1)" },
        { G::Aperture, "--spread METHOD", "spread",
          "Disc, polygon and mask: bounded (default: constant time, large "
          "footprints merged in blocks of at most r/4 pixels, highlights exact) or "
          "exact (every pixel on its own: time grows with the blur)" },
        { G::Aperture, "--psf-image FILE", "psf-image",
          "The hybrid method: pixels whose bokeh is visible (bright highlights) are "
          "spread with this PSF image, scaled to their CoC; all others with the "
          "fast --aperture filter" },
        { G::Aperture, "--hybrid-threshold T", "hybrid-threshold",
          "Hybrid: a pixel's bokeh is visible when it is T times brighter than the "
          "mean over its CoC (default: 4)" },
    };
}

/// What in the input is read, and how it is cut into layers.
std::vector<ShotOption> scene_options()
{
    return {
        { G::Scene, "--view NAME", "view",
          "View of a multi-view EXR (default: the first part's view)" },
        { G::Scene, "--layer NAME", "layer",
          "Channel prefix of colour and depth, e.g. 'beauty' for beauty.R..beauty.Z, or "
          "Blender's view layer name (default: plain R,G,B,A,Z or the file's only "
          "prefixed set)" },
        { G::Scene, "--depth FILE|CHANNEL", "depth",
          "Depth for a render without Z, or instead of its Z: a channel of the input by "
          "name, or a depth image (its Z or only channel; a frame pattern for sequences)" },
        { G::Scene, "--depth-scale S", "depth-scale",
          "Metres per depth unit of the input's Z, e.g. 0.01 for centimetres (default: 1; "
          "--focus stays in metres)" },
        { G::Scene, "--layers N", "layers",
          "Depth layers to cut deep and flat inputs into, spaced evenly in CoC (default: "
          "0 = automatic: boundaries in the gaps between objects, at most 24 px of CoC "
          "per layer)" },
        { G::Scene, "--memory-limit SIZE", "memory-limit",
          "The most memory a frame's images may take, e.g. 12G or 512M. A file whose "
          "header asks for more (a giant data window, a deep file with billions of "
          "samples) is refused before anything is allocated (default: half the "
          "machine's memory)" },
    };
}

/// The input's and the output's colour spaces.
std::vector<ShotOption> color_options()
{
    return {
        { G::InputColor, "--colorconfig FILE", "colorconfig",
          "OCIO config (default: $OCIO, else the config shipped with defocus)" },
        { G::InputColor, "--iscolorspace NAME", "iscolorspace",
          "Colour space of the input (default: what the file names: its colorInteropID, "
          "a colour space tag the config has, or the chromaticities of AP0, AP1, Rec.709, "
          "P3-D65 or Rec.2020; else a guess, which -v reports)" },

        { G::OutputColor, "--tocolorspace NAME", "tocolorspace",
          "Colour space of the output (default: the input's), named in its header by "
          "chromaticities and colorInteropID" },
    };
}

/// What is written.
std::vector<ShotOption> output_options()
{
    return {
        { G::Output, "--output KIND", "output",
          "image: the defocused image (default); focusmap: where the focus falls, "
          "green in focus, red in front, blue behind, brighter with more blur, "
          "whitened where the blur reaches --max-blur" },
        { G::Output, "--aov NAME", "aov",
          "An extra channel: confidence, named 'confidence', the fraction of each "
          "pixel's light that came from surfaces the input hides (behind nearer "
          "objects of a flat render or deep image) and defocus rebuilt: 0 where all "
          "of it was seen, as everywhere for layered input; where it is high, look "
          "closely (default: none)" },
        { G::Output, "-d TYPE", "pixel-type",
          "Output pixel type: half or float (default: the input's)" },
        { G::Output, "--compression NAME", "compression",
          "Output compression, e.g. zip, piz, dwaa (default: the input's)" },
        { G::Output, "--crop", "window",
          "Clip the result to the display window (default: the input's data "
          "window, as oiiotool keeps it)",
          "display" },
        { G::Output, "--edge MODE", "edge",
          "Beyond the data window: extend (its edge pixels continue outwards, so "
          "the frame keeps its light to the corners), black (nothing), auto "
          "(default: extend where the data window does not cover the blur)" },
        { G::Output, "--grow", "window",
          "Grow the data window by the blur, keeping all of the light spread "
          "beyond the input's data window",
          "grown" },
    };
}

}  // namespace

const std::vector<ShotOption>& shot_options()
{
    static const std::vector<ShotOption> options = [] {
        std::vector<ShotOption> all;
        for (auto group : { sequence_options, camera_options, aperture_options, scene_options,
                            color_options, output_options }) {
            std::vector<ShotOption> options = group();
            all.insert(all.end(), options.begin(), options.end());
        }
        return all;
    }();
    return options;
}

const char* option_group_heading(OptionGroup group)
{
    switch (group) {
    case OptionGroup::Sequences: return "Sequences:";
    case OptionGroup::Camera:
        return "Camera (DIST, N and MM take keyframes FRAME:VALUE,... for a focus pull):";
    case OptionGroup::Aperture: return "Aperture:";
    case OptionGroup::Scene: return "Scene:";
    default: return "";
    }
}

}  // namespace defocus
