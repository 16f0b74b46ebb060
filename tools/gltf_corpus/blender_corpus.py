"""Writes the glTF corpus files that Blender's exporter makes, and what Blender's importer
sees in each: `tests/data/gltf/corpus/NAME.glb` and `NAME.expected.json`.

Run with Blender 5 as a Python module (`pip install bpy==5.0.0`, Python 3.11):

    python tools/gltf_corpus/blender_corpus.py tests/data/gltf/corpus [NAME...]

With NAMEs (`vertex_colors`, `second_uv_map`, ...; see FILES) only those files are written.

Each file is exported, then imported into an empty scene, and the importer's evaluated
meshes (modifiers, armatures and shape keys applied), world-space triangles in glTF's frame
(Y up), are summarised in `NAME.expected.json` (`shape`): the shape a correct reader draws
at the file's static pose.
"""

import json
import math
import sys
from pathlib import Path

import bpy


def empty_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def export(path, **options):
    """A GLB of the scene at its current frame, without animations."""
    bpy.ops.export_scene.gltf(
        filepath=str(path),
        export_format="GLB",
        export_animations=False,
        export_yup=True,
        **options,
    )


def evaluated_triangles():
    """Every mesh object's evaluated triangles, world space, glTF frame (x, z, -y)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    # The importer draws bones with a mesh of its own (an icosphere), which is no part of
    # the file's geometry.
    bone_shapes = {
        bone.custom_shape.name
        for obj in bpy.context.scene.objects
        if obj.type == "ARMATURE"
        for bone in obj.pose.bones
        if bone.custom_shape is not None
    }
    triangles = []
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or obj.name in bone_shapes:
            continue
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        mesh.calc_loop_triangles()
        world = evaluated.matrix_world
        for tri in mesh.loop_triangles:
            corners = []
            for v in tri.vertices:
                p = world @ mesh.vertices[v].co
                corners.append([p.x, p.z, -p.y])
            triangles.append(corners)
        evaluated.to_mesh_clear()
    return triangles


def shape(triangles):
    """What tests compare, independent of vertex order: the triangle count, the total area,
    the bounds, and the area-weighted mean and covariance of the triangles' centroids."""
    count, area = len(triangles), 0.0
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    first, second = [0.0] * 3, [[0.0] * 3 for _ in range(3)]
    for a, b, c in triangles:
        e1 = [b[i] - a[i] for i in range(3)]
        e2 = [c[i] - a[i] for i in range(3)]
        cross = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ]
        w = 0.5 * math.sqrt(sum(x * x for x in cross))
        centroid = [(a[i] + b[i] + c[i]) / 3.0 for i in range(3)]
        area += w
        for i in range(3):
            lo[i] = min(lo[i], a[i], b[i], c[i])
            hi[i] = max(hi[i], a[i], b[i], c[i])
            first[i] += w * centroid[i]
            for j in range(3):
                second[i][j] += w * centroid[i] * centroid[j]
    mean = [x / area for x in first]
    covariance = [[second[i][j] / area - mean[i] * mean[j] for j in range(3)] for i in range(3)]
    return {
        "triangles": count,
        "area": area,
        "min": lo,
        "max": hi,
        "mean": mean,
        "covariance": covariance,
    }


def write_expected(glb, out_json):
    empty_scene()
    bpy.ops.import_scene.gltf(filepath=str(glb))
    triangles = evaluated_triangles()
    out_json.write_text(json.dumps(shape(triangles), indent=1) + "\n")
    return len(triangles)


def skinned_arm(path):
    """A cylinder along +X with two bones; the forearm bone bent 90 degrees in the pose."""
    empty_scene()
    bpy.ops.mesh.primitive_cylinder_add(
        vertices=12, radius=0.1, depth=2.0, location=(1.0, 0.0, 0.0), rotation=(0.0, math.pi / 2, 0.0)
    )
    arm = bpy.context.active_object
    arm.name = "Arm"
    # Cuts along the length so the bend has vertices to move.
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.subdivide(number_cuts=7)
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.object.armature_add(location=(0.0, 0.0, 0.0))
    rig = bpy.context.active_object
    rig.name = "Rig"
    bpy.ops.object.mode_set(mode="EDIT")
    bones = rig.data.edit_bones
    upper = bones[0]
    upper.name = "Upper"
    upper.head = (0.0, 0.0, 0.0)
    upper.tail = (1.0, 0.0, 0.0)
    fore = bones.new("Fore")
    fore.head = (1.0, 0.0, 0.0)
    fore.tail = (2.0, 0.0, 0.0)
    fore.parent = upper
    fore.use_connect = True
    bpy.ops.object.mode_set(mode="OBJECT")
    arm.select_set(True)
    rig.select_set(True)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    bpy.ops.object.mode_set(mode="POSE")
    pose = rig.pose.bones["Fore"]
    pose.rotation_mode = "XYZ"
    pose.rotation_euler = (0.0, 0.0, math.radians(90.0))
    bpy.ops.object.mode_set(mode="OBJECT")
    export(path, export_skins=True, export_rest_position_armature=False)


def morph_box(path):
    """A cube with two shape keys at 0.7 and 0.25: the top pulled up, one side pushed in."""
    empty_scene()
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    cube = bpy.context.active_object
    cube.name = "Morphed"
    cube.shape_key_add(name="Basis")
    up = cube.shape_key_add(name="Up")
    for v in up.data:
        if v.co.z > 0:
            v.co.z += 1.0
    up.value = 0.7
    side = cube.shape_key_add(name="Side")
    for v in side.data:
        if v.co.x > 0:
            v.co.x -= 0.4
    side.value = 0.25
    export(path, export_morph=True, export_morph_normal=True)


def crowd(path):
    """Twenty linked duplicates of one mesh (a monkey) on a 5 x 4 grid, turned and scaled."""
    empty_scene()
    bpy.ops.mesh.primitive_monkey_add(size=0.5)
    first = bpy.context.active_object
    first.name = "Monkey0"
    for i in range(20):
        obj = first if i == 0 else first.copy()
        if i:
            obj.name = f"Monkey{i}"
            bpy.context.collection.objects.link(obj)
        obj.location = ((i % 5) * 1.2, (i // 5) * 1.2, 0.0)
        obj.rotation_euler = (0.0, 0.0, math.radians(18.0 * i))
        obj.scale = (1.0 + 0.05 * i,) * 3
    export(path)


def draco(path):
    """The crowd's monkey alone, compressed with Blender's Draco library."""
    empty_scene()
    bpy.ops.mesh.primitive_monkey_add(size=1.0)
    bpy.ops.object.shade_smooth()
    export(
        path,
        export_draco_mesh_compression_enable=True,
        export_draco_mesh_compression_level=6,
        export_draco_position_quantization=14,
        export_draco_normal_quantization=10,
        export_draco_texcoord_quantization=12,
    )


def animated(path):
    """A cube that slides along X between frames 1 and 24: one animation, not played."""
    empty_scene()
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    cube = bpy.context.active_object
    cube.keyframe_insert(data_path="location", frame=1)
    cube.location = (2.0, 0.0, 0.0)
    cube.keyframe_insert(data_path="location", frame=24)
    bpy.context.scene.frame_set(1)
    bpy.ops.export_scene.gltf(
        filepath=str(path), export_format="GLB", export_animations=True, export_yup=True
    )


# Face colours of `vertex_colors`, linear RGBA, one per quad of its 2 x 2 grid.
FACE_COLORS = [
    (0.8, 0.2, 0.1, 1.0),
    (0.1, 0.7, 0.3, 1.0),
    (0.2, 0.3, 0.9, 1.0),
    (0.5, 0.5, 0.5, 1.0),
]


def lambertian(material, base_color):
    """`material`'s Principled BSDF as glTF's exporter reads it: `base_color`, not metallic,
    fully rough, with no specular layer (KHR_materials_specular's factor 0)."""
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = base_color
    bsdf.inputs["Metallic"].default_value = 0.0
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    return bsdf


def vertex_colors(path, **options):
    """A 2 x 2 m plane of 2 x 2 quads, each quad's corners one colour of FACE_COLORS (a
    float colour attribute on face corners), with a base colour factor: COLOR_0."""
    empty_scene()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=2, y_subdivisions=2, size=2.0)
    plane = bpy.context.active_object
    mesh = plane.data
    colors = mesh.color_attributes.new("Col", "FLOAT_COLOR", "CORNER")
    mesh.color_attributes.active_color = colors
    for face in mesh.polygons:
        for corner in face.loop_indices:
            colors.data[corner].color = FACE_COLORS[face.index]
    material = bpy.data.materials.new("tinted")
    material.use_nodes = True
    lambertian(material, (0.9, 0.8, 0.6, 1.0))
    mesh.materials.append(material)
    export(path, export_vertex_color="ACTIVE", **options)


def vertex_colors_draco(path):
    """`vertex_colors` compressed with Blender's Draco library, colours included."""
    vertex_colors(
        path,
        export_draco_mesh_compression_enable=True,
        export_draco_position_quantization=14,
        export_draco_color_quantization=10,
    )


# The texels of `second_uv_map`'s image, sRGB bytes: each 4 x 4 quadrant of the 8 x 8 image
# one colour, top-left, top-right, bottom-left, bottom-right as the image shows them.
QUADRANTS = [(200, 40, 40), (40, 200, 40), (40, 40, 200), (220, 220, 60)]


def second_uv_map(path):
    """A 2 x 2 m plane with two UV maps: the first spans the image, the second is it
    mirrored along u. Its base colour texture (an 8 x 8 image of four solid quadrants)
    reads the second through a UV Map node, which the exporter writes as texCoord 1."""
    empty_scene()
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    mesh = plane.data
    first = mesh.uv_layers[0]
    second = mesh.uv_layers.new(name="Mirrored")
    for k, loop in enumerate(first.data):
        u, v = loop.uv
        second.data[k].uv = (1.0 - u, v)
    image = bpy.data.images.new("quadrants", 8, 8, alpha=False)
    pixels = []
    # Blender's rows run up from the image's bottom edge.
    for y in range(8):
        for x in range(8):
            top, right = y >= 4, x >= 4
            q = (0 if top else 2) + (1 if right else 0)
            pixels += [c / 255.0 for c in QUADRANTS[q]] + [1.0]
    image.pixels = pixels
    image.file_format = "PNG"
    image.pack()
    material = bpy.data.materials.new("second set")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = lambertian(material, (1.0, 1.0, 1.0, 1.0))
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Closest"
    uv_map = nodes.new("ShaderNodeUVMap")
    uv_map.uv_map = "Mirrored"
    links.new(uv_map.outputs["UV"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    mesh.materials.append(material)
    export(path)


# `materials`' spheres, left to right along glTF's x: (name, centre x, base colour). Each
# layered sphere has a plain twin of the same base, so that a test can tell the layer's
# effect from the base's.
SPHERES = [
    ("coated", -4.0, (0.8, 0.1, 0.1, 1.0)),
    ("red", -2.0, (0.8, 0.1, 0.1, 1.0)),
    ("flat", 0.0, (0.2, 0.7, 0.3, 1.0)),
    ("velvet", 2.0, (0.1, 0.1, 0.6, 1.0)),
    ("blue", 4.0, (0.1, 0.1, 0.6, 1.0)),
]

# The camera both renderers see `materials` through, in glTF's frame (Y up): position,
# the point it looks at, the vertical field of view in degrees, and the image size.
MATERIALS_CAMERA = ((0.0, 1.5, 11.0), (0.0, 0.0, 0.0), 30.0, (240, 80))


def materials(path):
    """Five spheres of radius 0.9, one material each, as Blender's exporter writes them: a
    red rough base under a full clear coat (KHR_materials_clearcoat) and the same base
    bare, a green unlit surface (the importer's light-path arrangement, which the
    exporter writes as KHR_materials_unlit), and a blue base under white sheen
    (KHR_materials_sheen) and the same base bare."""
    empty_scene()
    for name, x, color in SPHERES:
        # Blender's (x, y, z) is glTF's (x, -z, y).
        bpy.ops.mesh.primitive_uv_sphere_add(
            segments=48, ring_count=24, radius=0.9, location=(x, 0.0, 0.0)
        )
        sphere = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        material = bpy.data.materials.new(name)
        material.use_nodes = True
        nodes, links = material.node_tree.nodes, material.node_tree.links
        bsdf = nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = color
        bsdf.inputs["Roughness"].default_value = 0.6
        if name == "coated":
            bsdf.inputs["Coat Weight"].default_value = 1.0
            bsdf.inputs["Coat Roughness"].default_value = 0.1
        elif name in ("velvet", "blue"):
            bsdf.inputs["Roughness"].default_value = 0.8
        if name == "velvet":
            bsdf.inputs["Sheen Weight"].default_value = 1.0
            bsdf.inputs["Sheen Tint"].default_value = (1.0, 1.0, 1.0, 1.0)
            bsdf.inputs["Sheen Roughness"].default_value = 0.3
        elif name == "flat":
            nodes.remove(bsdf)
            output = nodes["Material Output"]
            emission = nodes.new("ShaderNodeEmission")
            emission.inputs["Color"].default_value = color
            light_path = nodes.new("ShaderNodeLightPath")
            transparent = nodes.new("ShaderNodeBsdfTransparent")
            mix = nodes.new("ShaderNodeMixShader")
            links.new(mix.inputs["Fac"], light_path.outputs["Is Camera Ray"])
            links.new(mix.inputs[1], transparent.outputs[0])
            links.new(mix.inputs[2], emission.outputs[0])
            links.new(output.inputs["Surface"], mix.outputs[0])
        sphere.data.materials.append(material)
    export(path)


def cycles_exr(scene, samples, width, height):
    """Cycles on the CPU at `samples` a pixel, seed 1, no denoising, `width` × `height`,
    the film transparent, the Standard view transform, writing 32-bit linear EXR."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"


def materials_cycles(glb, out_exr):
    """Blender's import of `materials` rendered by Cycles on the CPU through
    MATERIALS_CAMERA, lit by a uniform white world of radiance 1 (linear EXR, alpha
    where the spheres are): the shaded reference `tests/gltf_corpus.rs` compares with."""
    empty_scene()
    bpy.ops.import_scene.gltf(filepath=str(glb))
    scene = bpy.context.scene
    (px, py, pz), (tx, ty, tz), vfov, (width, height) = MATERIALS_CAMERA
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(vfov)
    camera = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(camera)
    from mathutils import Vector

    position, target = Vector((px, -pz, py)), Vector((tx, -tz, ty))
    camera.location = position
    camera.rotation_euler = (target - position).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    world = bpy.data.worlds.new("white")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    scene.world = world
    cycles_exr(scene, 1024, width, height)
    scene.cycles.max_bounces = 8
    scene.render.filepath = str(out_exr)
    bpy.ops.render.render(write_still=True)


def materials_joined(path):
    """`materials`' five spheres joined into one object (one root node), its origin moved
    off the centre: a file that the dataset scripts, which scale each root object about
    its own origin, normalise as meshtrace does."""
    materials(path.with_name("materials_joined_source.glb"))
    empty_scene()
    bpy.ops.import_scene.gltf(filepath=str(path.with_name("materials_joined_source.glb")))
    path.with_name("materials_joined_source.glb").unlink()
    spheres = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    for o in spheres:
        o.select_set(True)
    bpy.context.view_layer.objects.active = spheres[0]
    bpy.ops.object.join()
    joined = bpy.context.active_object
    bpy.ops.object.origin_set(type="ORIGIN_GEOMETRY")
    joined.location = (0.3, -0.2, 0.1)
    export(path)


def normalised_scene(glb, factory=True, as_one=False):
    """The factory scene (made anew unless `factory` is false, for a scene the caller has
    begun) with its Cube removed and `glb` imported and normalised as the Zero123,
    objaverse-rendering and SyncDreamer scripts do (each root object scaled about its own
    origin, then the box centred on the origin), or with `as_one` as Objaverse-XL's does
    (every root object but the camera parented to one empty at the origin, which is
    scaled and moved);
    the cameras, lights and empties kept."""
    from mathutils import Vector

    if factory:
        bpy.ops.wm.read_factory_settings()
    scene = bpy.context.scene
    for o in list(scene.objects):
        if o.type not in ("CAMERA", "LIGHT", "EMPTY"):
            bpy.data.objects.remove(o, do_unlink=True)
    bpy.ops.import_scene.gltf(filepath=str(glb), merge_vertices=True)

    def bbox():
        lo, hi = Vector((math.inf,) * 3), Vector((-math.inf,) * 3)
        for o in scene.objects:
            if o.type == "MESH":
                for c in o.bound_box:
                    p = o.matrix_world @ Vector(c)
                    lo = Vector(map(min, lo, p))
                    hi = Vector(map(max, hi, p))
        return lo, hi

    if as_one:
        parent = bpy.data.objects.new("ParentEmpty", None)
        scene.collection.objects.link(parent)
        # The script's camera keeps its world position (its `.npy` poses put it on the
        # shell about the world origin, whatever the object's size): it is left out.
        for o in scene.objects:
            if o.parent is None and o != parent and o.type != "CAMERA":
                o.parent = parent
    lo, hi = bbox()
    scale = 1 / max(hi - lo)
    for o in scene.objects:
        if o.parent is None:
            o.scale = o.scale * scale
    bpy.context.view_layer.update()
    lo, hi = bbox()
    offset = -(lo + hi) / 2
    for o in scene.objects:
        if o.parent is None:
            o.matrix_world.translation += offset
    bpy.context.view_layer.update()
    return scene


def ring_cycles(scene, out_dir, views, count, size, distance):
    """Renders `scene` by Cycles from views `views` of `count` on a ring at 30° and
    `distance` (`cycles_views`)."""
    cameras = {}
    for i in views:
        az, el = i / count * 2 * math.pi, math.radians(30)
        cameras[i] = (
            distance * math.cos(az) * math.cos(el),
            distance * math.sin(az) * math.cos(el),
            distance * math.sin(el),
        )
    cycles_views(scene, out_dir, cameras, size)


def cycles_views(
    scene, out_dir, cameras, size, target=None, lens=35, filter_width=0.01, normals=False
):
    """Renders `scene` by Cycles on the CPU (256 samples, no denoising, the scripts'
    bounces and `filter_width`, linear EXR with alpha, `VIEW.exr`) from each camera
    position of `cameras` (view: position), through the factory Camera with a `lens` mm
    lens on 32 mm, tracking `target` (an empty at the origin when None) as the scripts'
    TRACK_TO constraint does. With `normals`, the Normal pass too, in a multilayer EXR
    (`ViewLayer.Normal.X`, ...; Blender 5's `MULTI_LAYER_IMAGE`), at 64 samples."""
    camera = scene.objects["Camera"]
    camera.data.lens, camera.data.sensor_width = lens, 32
    if target is None:
        target = bpy.data.objects.new("Empty", None)
        scene.collection.objects.link(target)
    track = camera.constraints.new(type="TRACK_TO")
    track.track_axis, track.up_axis, track.target = "TRACK_NEGATIVE_Z", "UP_Y", target
    cycles_exr(scene, 64 if normals else 256, size, size)
    scene.cycles.diffuse_bounces, scene.cycles.glossy_bounces = 1, 1
    scene.cycles.transparent_max_bounces, scene.cycles.transmission_bounces = 3, 3
    scene.cycles.filter_width = filter_width
    if normals:
        for layer in scene.view_layers:
            layer.use_pass_normal = True
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    for i, position in cameras.items():
        camera.location = position
        bpy.context.view_layer.update()
        scene.render.filepath = str(out_dir / f"{i:03d}.exr")
        bpy.ops.render.render(write_still=True)


def syncdreamer_cycles(glb, out_dir, views):
    """SyncDreamer's blender_script.py (`--camera_type fixed`) on `glb`: the factory point
    light kept, a world of grey 0.5, 16 views at 1.5, 256². The reference for meshtrace's
    syncdreamer preset."""
    scene = normalised_scene(glb)
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    background.inputs["Strength"].default_value = 1.0
    ring_cycles(scene, out_dir, views, 16, 256, 1.5)


def objaverse_cycles(glb, out_dir, views):
    """allenai/objaverse-rendering's blender_script.py on `glb`, run with `--engine
    CYCLES` (its default is EEVEE, which needs a display): the factory Light deleted, its
    area light of 30,000 W (1 m, scale 100) at (0, 0, 0.5), the factory world, 12 views at
    1.5, 512². The reference for meshtrace's objaverse preset."""
    scene = normalised_scene(glb)
    bpy.data.objects.remove(scene.objects["Light"], do_unlink=True)
    bpy.ops.object.light_add(type="AREA")
    light = bpy.context.active_object
    light.data.energy = 30000
    light.location = (0, 0, 0.5)
    light.scale = (100, 100, 100)
    ring_cycles(scene, out_dir, views, 12, 512, 1.5)


def uniform(uid, view, dim):
    """meshtrace's `math::uniform`: the number in [0, 1) a preset draws for object `uid`,
    view `view` and dimension `dim` (FNV-1a of the uid, mixed by SplitMix64's finaliser)."""
    mask = (1 << 64) - 1
    h = 0xCBF29CE484222325
    for b in uid.encode():
        h = ((h ^ b) * 0x100000001B3) & mask
    x = h ^ ((((view << 32) | dim) * 0x9E3779B97F4A7C15) & mask)
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & mask
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & mask
    x ^= x >> 31
    return (x >> 11) / float(1 << 53)


def zero123_cycles(glb, out_dir, views, uid="spheres"):
    """cvlab-columbia/zero123's objaverse-rendering/scripts/blender_script.py on `glb`: its
    area light made at the start (1 m, scale 100) and normalised with the object, the
    factory Light and world kept; then the light's draws and the views' cameras on the
    shell of radius 1.5-2.2, as meshtrace's zero123 preset draws them for `uid`
    (`uniform(uid, 2^32 - 1, k)` for the light, `uniform(uid, view, k)` and `2^16` for a
    camera), 512². The reference for meshtrace's zero123 preset: `tests/batch.rs` renders
    the file as `spheres.glb`, whose uid is `spheres`."""
    bpy.ops.wm.read_factory_settings()
    bpy.ops.object.light_add(type="AREA")
    bpy.context.active_object.scale = (100, 100, 100)
    scene = normalised_scene(glb, factory=False)
    light = scene.objects["Area"]
    obj = (1 << 32) - 1
    light.data.energy = 300 + 300 * uniform(uid, obj, 0)
    light.location = (
        2 * uniform(uid, obj, 1) - 1,
        2 * uniform(uid, obj, 2) - 1,
        0.5 + uniform(uid, obj, 3),
    )
    cycles_views(scene, out_dir, shell_cameras(uid, views), 512)


def shell_cameras(uid, views):
    """The cameras of Zero123's shell (radius 1.5-2.2) that meshtrace's presets draw for
    `uid`: view: position."""
    cameras = {}
    for view in views:
        d = [2 * uniform(uid, view, k) - 1 for k in range(3)]
        norm = math.sqrt(sum(c * c for c in d))
        radius = 1.5 + 0.7 * uniform(uid, view, 1 << 16)
        cameras[view] = tuple(c / norm * radius for c in d)
    return cameras


def objaverse_xl_cycles(glb, out_dir, views, uid="spheres"):
    """allenai/objaverse-xl's scripts/rendering/blender_script.py on `glb`, run with Cycles:
    its camera's tracking target made at the start and normalised with the object (the
    script parents every root object to one empty and normalises that), the lights replaced
    by its four suns without shadows at the script's rotations, their strengths picked as
    meshtrace's objaverse-xl preset picks them for `uid` (the k-th of three by
    `uniform(uid, 2^32 - 1, k)`), the factory world; the cameras of the same uid on the shell,
    512². The reference for meshtrace's objaverse-xl preset."""
    bpy.ops.wm.read_factory_settings()
    target = bpy.data.objects.new("Target", None)
    bpy.context.scene.collection.objects.link(target)
    scene = normalised_scene(glb, factory=False, as_one=True)
    for o in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(o, do_unlink=True)
    suns = [
        ((0.785398, 0, -0.785398), [3, 4, 5]),
        ((0.785398, 0, 2.35619), [2, 3, 4]),
        ((-0.785398, 0, -3.92699), [3, 4, 5]),
        ((3.14159, 0, 0), [1, 2, 3]),
    ]
    for k, (rotation, choices) in enumerate(suns):
        data = bpy.data.lights.new(name=f"Sun{k}", type="SUN")
        data.use_shadow = False
        data.energy = choices[min(int(3 * uniform(uid, (1 << 32) - 1, k)), 2)]
        sun = bpy.data.objects.new(f"Sun{k}", data)
        scene.collection.objects.link(sun)
        sun.rotation_euler = rotation
    cycles_views(scene, out_dir, shell_cameras(uid, views), 512, target)


def trellis_angles(uid, views, count):
    """The yaw and pitch (radians) of views `views` of `count` on TRELLIS's Hammersley
    sphere, with the offsets meshtrace's trellis preset draws for `uid`
    (`uniform(uid, 2^32 - 1, 10)` and `11`), as `dataset_toolkits/render.py` passes them
    to its Blender script: view: (yaw, pitch)."""
    o0, o1 = uniform(uid, (1 << 32) - 1, 10), uniform(uid, (1 << 32) - 1, 11)
    angles = {}
    for i in views:
        u = i / count + o0 / count
        v = int(f"{i:032b}"[::-1], 2) / 2**32 + o1
        u = 2 * u if u < 0.25 else 2 / 3 * u + 1 / 3
        angles[i] = (2 * math.pi * v, math.acos(1 - 2 * u) - math.pi / 2)
    return angles


def trellis_cycles(glb, out_dir, views, uid="spheres", count=150, size=512, normals=False):
    """microsoft/TRELLIS's dataset_toolkits/blender_script/render.py on `glb`: the object
    normalised first (its root objects under one empty), then the lights made in the
    normalised frame (a point light of 1,000 W at (4, 1, 6), an area light of 10,000 W,
    0.25 m scaled by 100, at (0, 0, 10) facing down, and the one of 1,000 W at (0, 0, -10)
    that faces away), the factory world; views of `count` on the Hammersley sphere of
    radius 2 with the offsets meshtrace's trellis preset draws for `uid`
    (`trellis_angles`), a 40° field of view, `filter_width` 1,
    `size`². The reference for meshtrace's trellis preset; with `normals`, for its
    `save_normal` (cycles_views)."""
    bpy.ops.wm.read_factory_settings()
    bpy.data.objects.remove(bpy.context.scene.objects["Light"], do_unlink=True)
    scene = normalised_scene(glb, factory=False, as_one=True)
    for name, kind, energy, location, scale in [
        ("Default_Light", "POINT", 1000, (4, 1, 6), 1),
        ("Top_Light", "AREA", 10000, (0, 0, 10), 100),
        ("Bottom_Light", "AREA", 1000, (0, 0, -10), 1),
    ]:
        light = bpy.data.objects.new(name, bpy.data.lights.new(name, type=kind))
        scene.collection.objects.link(light)
        light.data.energy = energy
        light.location = location
        light.scale = (scale, scale, scale)
    cameras = {}
    for i, (yaw, pitch) in trellis_angles(uid, views, count).items():
        cameras[i] = (
            2 * math.cos(yaw) * math.cos(pitch),
            2 * math.sin(yaw) * math.cos(pitch),
            2 * math.sin(pitch),
        )
    lens = 16 / math.tan(math.radians(20))
    cycles_views(scene, out_dir, cameras, size, lens=lens, filter_width=1.0, normals=normals)


# Every file, by name; `python blender_corpus.py OUT NAME...` writes only those named.
FILES = [
    ("skinned_arm", skinned_arm),
    ("morph_box", morph_box),
    ("crowd", crowd),
    ("draco_monkey", draco),
    ("animated_cube", animated),
    ("vertex_colors", vertex_colors),
    ("vertex_colors_draco", vertex_colors_draco),
    ("second_uv_map", second_uv_map),
    ("materials", materials),
    ("materials_joined", materials_joined),
]


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    only = sys.argv[2:]
    for name, make in FILES:
        if only and name not in only:
            continue
        glb = out / f"{name}.glb"
        make(glb)
        n = write_expected(glb, out / f"{name}.expected.json")
        print(f"{glb}: {n} triangles as Blender imports it")
        if name == "materials":
            materials_cycles(glb, out / "materials.cycles.exr")
        if name == "materials_joined":
            for preset, views, render in [
                ("syncdreamer", [0, 5], syncdreamer_cycles),
                ("objaverse", [0, 7], objaverse_cycles),
                ("zero123", [0, 1], zero123_cycles),
                ("objaverse-xl", [0, 1], objaverse_xl_cycles),
                # Two views of two: the test renders the preset with `views = 2`.
                ("trellis", [0, 1], lambda g, f, v: trellis_cycles(g, f, v, count=2)),
                # TRELLIS's --save_normal: the Normal pass of the same two views, 128².
                (
                    "trellis-normal",
                    [0, 1],
                    lambda g, f, v: trellis_cycles(g, f, v, count=2, size=128, normals=True),
                ),
            ]:
                folder = out / f"{preset}.cycles"
                folder.mkdir(exist_ok=True)
                render(glb, folder, views)


if __name__ == "__main__":
    main()
