# Imports BVH files with Blender's own importer and dumps pose-bone head positions (world, after
# the importer's axis conversion and scale) for a few frames, so tests/io/test_blender_bvh.cpp can
# compare them with Kinegraph's forward kinematics.
#
#   blender -b --factory-startup --python tests/io/blender_import_bvh.py -- \
#       in.bvh out.tsv [in2.bvh out2.tsv ...]
#
# Import options: global_scale 1 (the test writes its BVH files in metres), axis_forward -Z and
# axis_up Y (the BVH convention, which Blender turns Z-up: file (x, y, z) -> Blender (x, -z, y)),
# rotate_mode NATIVE (each bone keeps the file's Euler order), frame_start 1 (BVH frame f is
# Blender frame f + 1). Output: one line per frame and bone, "frame<TAB>bone<TAB>x<TAB>y<TAB>z",
# for 5 frames spread over the clip (first and last included).
import builtins
import sys

# Debian's Blender 3.4 runs on Python 3.11, whose open() refuses the importer's mode 'rU'.
_open = builtins.open


def _open_without_u(file, mode="r", *args, **kwargs):
    if isinstance(mode, str) and "U" in mode:
        mode = mode.replace("U", "") or "r"
    return _open(file, mode, *args, **kwargs)


builtins.open = _open_without_u

import bpy  # noqa: E402


def frames_to_dump(count):
    if count <= 5:
        return list(range(count))
    return sorted({round(k * (count - 1) / 4) for k in range(5)})


def dump(in_path, out_path):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    result = bpy.ops.import_anim.bvh(
        filepath=in_path,
        target="ARMATURE",
        global_scale=1.0,
        frame_start=1,
        use_fps_scale=False,
        update_scene_fps=False,
        update_scene_duration=True,
        rotate_mode="NATIVE",
        axis_forward="-Z",
        axis_up="Y",
    )
    if result != {"FINISHED"}:
        raise RuntimeError("import of %s: %s" % (in_path, result))
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    with open(in_path) as f:
        count = next(int(line.split()[1]) for line in f if line.strip().lower().startswith("frames:"))
    scene = bpy.context.scene
    with open(out_path, "w") as out:
        for frame in frames_to_dump(count):
            scene.frame_set(frame + 1)
            for bone in arm.pose.bones:
                head = arm.matrix_world @ bone.head
                out.write("%d\t%s\t%.9f\t%.9f\t%.9f\n" % (frame, bone.name, head.x, head.y, head.z))


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) < 2 or len(argv) % 2:
        print("usage: blender -b --python blender_import_bvh.py -- in.bvh out.tsv [in.bvh out.tsv ...]")
        sys.exit(2)
    for i in range(0, len(argv), 2):
        dump(argv[i], argv[i + 1])


try:
    main()
except Exception as e:  # a failure must reach the test as an exit code, not a hung UI
    import traceback

    traceback.print_exc()
    sys.exit(1)
