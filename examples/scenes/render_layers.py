# Renders a test scene with Blender 3.4 Cycles: each layer alone and the
# whole scene through a pinhole camera (with an overscan margin), and the
# whole scene through the thin-lens camera (the truth). Every surface is
# emissive and light does not bounce, so the layers are exactly separable:
# the correct layered result is determined by the layers alone.
#
#   blender -b --factory-startup -P render_layers.py -- SCENE OUTDIR
#
# SCENE is "poles" or "lattice" (see the functions below). Writes Blender's
# multilayer EXRs into OUTDIR: layer_<name>.exr, flat.exr and
# truth_focus<F>.exr; assemble_scene.py turns them into the scene's files.
import math
import sys

import bpy

WIDTH, HEIGHT = 480, 270     # the display window
OVERSCAN = 48                # pixels of margin around it in the inputs
FOCAL_MM, SENSOR_MM, FSTOP = 85.0, 36.0, 2.0
INPUT_SAMPLES, TRUTH_SAMPLES = 256, 4096


def emission_material(name, colour_node):
    """A material that only emits: colour_node(tree) returns the socket of
    its colour, or a colour tuple."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], out.inputs["Surface"])
    colour = colour_node(tree)
    if isinstance(colour, tuple):
        emission.inputs["Color"].default_value = colour + (1.0,)
    else:
        tree.links.new(colour, emission.inputs["Color"])
    return material


def checker(scale, a, b):
    def make(tree):
        node = tree.nodes.new("ShaderNodeTexChecker")
        node.inputs["Scale"].default_value = scale
        node.inputs["Color1"].default_value = a + (1.0,)
        node.inputs["Color2"].default_value = b + (1.0,)
        return node.outputs["Color"]
    return make


def bricks(scale):
    def make(tree):
        node = tree.nodes.new("ShaderNodeTexBrick")
        node.inputs["Scale"].default_value = scale
        node.inputs["Color1"].default_value = (0.55, 0.2, 0.12, 1.0)
        node.inputs["Color2"].default_value = (0.35, 0.12, 0.08, 1.0)
        node.inputs["Mortar"].default_value = (0.8, 0.8, 0.75, 1.0)
        return node.outputs["Color"]
    return make


def stripes(scale, a, b):
    """Bands along the object's generated coordinates: a striped torus or
    sphere, a pattern that runs on behind whatever covers it."""
    def make(tree):
        wave = tree.nodes.new("ShaderNodeTexWave")
        wave.inputs["Scale"].default_value = scale
        wave.inputs["Distortion"].default_value = 0.0
        ramp = tree.nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.interpolation = "CONSTANT"
        ramp.color_ramp.elements[0].color = a + (1.0,)
        ramp.color_ramp.elements[1].position = 0.5
        ramp.color_ramp.elements[1].color = b + (1.0,)
        tree.links.new(wave.outputs["Fac"], ramp.inputs["Fac"])
        return ramp.outputs["Color"]
    return make


def add(layer, obj, material):
    obj.data.materials.append(material)
    for collection in obj.users_collection:
        collection.objects.unlink(obj)
    bpy.data.collections[layer].objects.link(obj)
    return obj


def metres(pixels, depth):
    """The size at `depth` of `pixels` of the display window."""
    return pixels * depth * SENSOR_MM / (FOCAL_MM * WIDTH)


def plane(layer, depth, at, size, material):
    """A rectangle facing the lens, centred `at` pixels from the frame's
    centre (y up), `size` pixels across."""
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(metres(at[0], depth),
                                                         metres(at[1], depth), -depth))
    obj = bpy.context.active_object
    obj.scale = (metres(size[0], depth), metres(size[1], depth), 1.0)
    return add(layer, obj, material)


def light(layer, depth, at, radius, colour, strength):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=metres(radius, depth),
                                         location=(metres(at[0], depth), metres(at[1], depth),
                                                   -depth),
                                         segments=24, ring_count=12)
    return add(layer, bpy.context.active_object,
               emission_material("light", lambda tree: tuple(c * strength for c in colour)))


def bar(layer, depth, at, size, colour):
    return plane(layer, depth, at, size, emission_material("bar", lambda tree: colour))


def poles():
    """Thin blurred poles before a checker wall, lights half hidden by
    them, and a striped torus behind the blurred edge of a near card."""
    wall = emission_material("wall", checker(60.0, (0.9, 0.85, 0.7), (0.1, 0.12, 0.15)))
    plane("far", 8.0, (0, 0), (900, 600), wall)
    for at, colour in (((-84, 40), (1.0, 0.8, 0.5)), ((20, 50), (0.5, 0.7, 1.0)),
                       ((104, 60), (1.0, 0.4, 0.3)), ((-170, -70), (0.6, 1.0, 0.5))):
        light("lights", 4.5, at, 4, colour, 25.0)
    depth = 2.2
    bpy.ops.mesh.primitive_torus_add(location=(metres(90, depth), metres(-60, depth), -depth),
                                     major_radius=metres(50, depth),
                                     minor_radius=metres(15, depth), rotation=(1.2, 0.3, 0.0))
    add("mid", bpy.context.active_object,
        emission_material("torus", stripes(6.0, (0.9, 0.9, 0.2), (0.1, 0.3, 0.8))))
    for x in (-80, 16, 100):
        bar("near", 1.0, (x, 0), (8, 600), (0.05, 0.05, 0.05))
    bar("near", 0.7, (150, -90), (100, 80), (0.6, 0.3, 0.3))


def lattice():
    """A lattice of thin bars near the lens before small lights, a striped
    sphere in focus and a brick wall."""
    plane("far", 10.0, (0, 0), (900, 600), emission_material("wall", bricks(40.0)))
    for k in range(7):
        light("lights", 6.0, (-180 + 60 * k, (50, 0, -50)[k % 3]), 3,
              (1.0, 0.9, 0.6) if k % 2 else (0.6, 0.8, 1.0), 20.0)
    depth = 3.0
    bpy.ops.mesh.primitive_uv_sphere_add(radius=metres(80, depth),
                                         location=(metres(-30, depth), metres(-20, depth),
                                                   -depth),
                                         segments=64, ring_count=32)
    add("mid", bpy.context.active_object,
        emission_material("sphere", stripes(4.0, (0.8, 0.2, 0.2), (0.9, 0.9, 0.9))))
    for x in range(-160, 161, 80):
        bar("near", 0.9, (x, 0), (6, 600), (0.02, 0.03, 0.02))
    for y in (-60, 20, 100):
        bar("near", 0.9, (0, y), (900, 5), (0.02, 0.03, 0.02))


SCENES = {"poles": poles, "lattice": lattice}
LAYERS = ("far", "lights", "mid", "near")


def set_up(scene_name):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
    scene.cycles.seed = 1
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_layers[0].use_pass_z = True
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0.0, 0.0, 0.0)
    for name in LAYERS:
        scene.collection.children.link(bpy.data.collections.new(name))
    camera = bpy.data.cameras.new("camera")
    camera.lens = FOCAL_MM
    camera.sensor_fit = "HORIZONTAL"
    camera.dof.aperture_fstop = FSTOP
    camera.dof.aperture_blades = 0
    obj = bpy.data.objects.new("camera", camera)
    scene.collection.objects.link(obj)
    scene.camera = obj
    SCENES[scene_name]()
    return scene, camera


def render(scene, path, samples, width, height, sensor_mm):
    scene.cycles.samples = samples
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.camera.data.sensor_width = sensor_mm
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def main():
    scene_name, out = sys.argv[sys.argv.index("--") + 1:][:2]
    scene, camera = set_up(scene_name)
    wide = (WIDTH + 2 * OVERSCAN, HEIGHT + 2 * OVERSCAN, SENSOR_MM * (WIDTH + 2 * OVERSCAN) / WIDTH)
    camera.dof.use_dof = False
    for name in LAYERS:
        for other in LAYERS:
            bpy.data.collections[other].hide_render = other != name
        render(scene, f"{out}/layer_{name}.exr", INPUT_SAMPLES, *wide)
    for other in LAYERS:
        bpy.data.collections[other].hide_render = False
    render(scene, f"{out}/flat.exr", INPUT_SAMPLES, *wide)
    camera.dof.use_dof = True
    for focus in FOCI[scene_name]:
        camera.dof.focus_distance = focus
        render(scene, f"{out}/truth_focus{focus:g}.exr", TRUTH_SAMPLES, WIDTH, HEIGHT, SENSOR_MM)


FOCI = {"poles": (3.0, 1.3), "lattice": (3.0, 1.5)}

if __name__ == "__main__":
    main()
