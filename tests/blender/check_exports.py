# Checks squeeze's exports in Blender, as a user of docs/render.md ("Blender") would open them:
# every export/NAME.obj imported with Blender's default OBJ importer (default axes), a Mesh Cache
# modifier with its default axes reading NAME.pc2, then NAME.mdd (Frame Start = the range's first
# frame), and export/animation.glb imported with Blender's glTF importer; at the range's first,
# middle and last frames every vertex must be within TOL of squeeze's own surface of that frame
# (export/obj/NAME_k.obj, full precision), in Blender's world coordinates (+Z up: squeeze's
# (x, y, z) is Blender's (x, -z, y)).
#
#   blender -b --factory-startup --python-exit-code 1 --python check_exports.py -- EXPORT_DIR FIRST LAST FPS
#
# Prints one line per object and check; raises (exit 1) on the first mismatch.
import os
import sys

import bpy

TOL = 1e-6  # m

argv = sys.argv[sys.argv.index("--") + 1:]
export_dir, first, last, fps = argv[0], int(argv[1]), int(argv[2]), float(argv[3])
frames = sorted({first, (first + last) // 2, last})
names = sorted(f[:-4] for f in os.listdir(export_dir) if f.endswith(".pc2"))
if not names:
    raise SystemExit(f"{export_dir}: no .pc2 files")


def reference(name, k):
    """squeeze's surface of object NAME at frame k, in Blender's axes."""
    pts = []
    with open(os.path.join(export_dir, "obj", f"{name}_{k:05d}.obj")) as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = map(float, line.split()[1:4])
                pts.append((x, -z, y))
    return pts


def world_vertices(ob):
    deps = bpy.context.evaluated_depsgraph_get()
    ev = ob.evaluated_get(deps)
    mesh = ev.to_mesh()
    m = ev.matrix_world
    pts = [tuple(m @ v.co) for v in mesh.vertices]
    ev.to_mesh_clear()
    return pts


def compare(label, ob, name):
    worst = 0.0
    for k in frames:
        bpy.context.scene.frame_set(k)
        got, want = world_vertices(ob), reference(name, k)
        if len(got) != len(want):
            raise RuntimeError(f"{label} {name}: frame {k}: {len(got)} vertices in Blender, {len(want)} in squeeze's frame")
        d = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(got, want))
        worst = max(worst, d)
        if d > TOL:
            raise RuntimeError(f"{label} {name}: frame {k}: a vertex is {d:.3g} m from squeeze's (tolerance {TOL:g} m)")
    a, b = reference(name, frames[0]), reference(name, frames[-1])
    moved = max(max(abs(p - q) for p, q in zip(u, v)) for u, v in zip(a, b))
    print(f"ok {label} {name}: {len(want)} vertices, frames {frames}, largest difference {worst:.2e} m "
          f"(the surface moves {moved:.3g} m over them)")


def empty_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps = int(round(fps))
    bpy.context.scene.render.fps_base = round(fps) / fps


for name in names:
    for fmt, ext in (("PC2", "pc2"), ("MDD", "mdd")):
        path = os.path.join(export_dir, f"{name}.{ext}")
        if not os.path.exists(path):
            continue
        empty_scene()
        bpy.ops.wm.obj_import(filepath=os.path.join(export_dir, f"{name}.obj"))  # default axes
        ob = bpy.context.selected_objects[0]
        mod = ob.modifiers.new("squeeze", "MESH_CACHE")  # default axes
        mod.cache_format = fmt
        mod.filepath = path
        mod.frame_start = first  # the cache's first sample is the range's first frame
        compare(f"obj+{ext}", ob, name)

glb = os.path.join(export_dir, "animation.glb")
if os.path.exists(glb):
    # Debian 12's Blender 3.4 glTF importer still uses np.bool, which numpy 1.24 (Debian 12's)
    # removed; the alias is the builtin bool (numpy's own deprecation note).
    import numpy
    if not hasattr(numpy, "bool") or "bool" in getattr(numpy, "__former_attrs__", {}):
        numpy.bool = bool
    empty_scene()
    bpy.ops.import_scene.gltf(filepath=glb)
    for name in names:
        ob = bpy.data.objects.get(name)
        if ob is None:
            raise RuntimeError(f"glb: no object named {name}")
        compare("glb", ob, name)
print("blender check: all exports match")
