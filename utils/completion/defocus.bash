# Bash completion for defocus, layerize and defocus-submit. The options are read from the
# tool's own --help when first completed, so they never drift from it;
# names and files are completed for the options that take them.

_defocus_options()
{
    local tool=$1 var="_defocus_options_${1//[^a-z]/_}"
    if [[ -z ${!var-} ]]; then
        # defocus-submit takes defocus's options too, for the shot.
        local helps
        helps=$("$tool" --help 2>/dev/null)
        [[ $tool == defocus-submit ]] && helps+=$'\n'$(defocus --help 2>/dev/null)
        printf -v "$var" '%s' "$(sed -nE 's/^ +(-[-a-z0-9]+).*/\1/p' <<< "$helps" \
            | sort -u | tr '\n' ' ')"
    fi
    printf '%s' "${!var}"
}

_defocus()
{
    local cur prev words cword
    _init_completion -n = || return
    case $prev in
        --aperture) COMPREPLY=($(compgen -W 'disc polygon mask: box tent smooth' -- "$cur"))
            [[ $cur == mask:* ]] && { compopt -o filenames; COMPREPLY=($(compgen -P mask: -f -- "${cur#mask:}")); }
            return ;;
        --spread) COMPREPLY=($(compgen -W 'bounded exact' -- "$cur")); return ;;
        --lens) COMPREPLY=($(compgen -W 'thin optical' -- "$cur")); return ;;
        --output) COMPREPLY=($(compgen -W 'image focusmap' -- "$cur")); return ;;
        --aov) COMPREPLY=($(compgen -W 'none confidence' -- "$cur")); return ;;
        --edge) COMPREPLY=($(compgen -W 'auto extend black' -- "$cur")); return ;;
        --camera-from-file) COMPREPLY=($(compgen -W 'on off' -- "$cur")); return ;;
        -d) COMPREPLY=($(compgen -W 'half float' -- "$cur")); return ;;
        --compression) COMPREPLY=($(compgen -W 'none rle zips zip piz pxr24 b44 b44a dwaa dwab' -- "$cur")); return ;;
        -o|--preview|--save-scene|--colorconfig|--psf-image|--depth)
            _filedir; return ;;
        --focus|--focus-at|--focal|--fstop|--sensor|--max-blur|--frames|--threads|--blades|\
        --rotation|--roundness|--aspect|--layers|--view|--layer|--memory-limit|--depth-scale|\
        --iscolorspace|--tocolorspace|--display|--display-view|--focus-tilt|--split-diopter|\
        --optical-centre|--axial-ca|--lateral-ca|--cateye|--hybrid-threshold|--focus-at-radius)
            return ;;  # a value only the user knows
    esac
    if [[ $cur == -* ]]; then
        COMPREPLY=($(compgen -W "$(_defocus_options "$1")" -- "$cur"))
    else
        _filedir '@(exr|dof|sxr|tif|tiff)'
    fi
}
complete -F _defocus defocus layerize defocus-submit
