# Imports GLBs into Blender headless and prints what a user would find: the mesh, its shape keys
# (morph targets, named after the shapes), its material's normal map and the animations.
#   blender -b --factory-startup --python scripts/blender-import.py -- FILE.glb [FILE.glb ...]
# Debian's Blender 3.4 glTF importer needs python3-numpy (apt-get install blender python3-numpy).
# Exit 0 when every file imported with at least one mesh, 1 otherwise.
import sys

import bpy

files = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
if not files:
    print('usage: blender -b --factory-startup --python scripts/blender-import.py -- FILE.glb ...')
    sys.exit(1)
ok = True
for path in files:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        bpy.ops.import_scene.gltf(filepath=path, import_shading='SMOOTH')
    except Exception as e:  # the importer reports its own traceback
        print(f'{path}: import failed: {e}')
        ok = False
        continue
    meshes = [o for o in bpy.context.scene.objects if o.type == 'MESH']
    if not meshes:
        print(f'{path}: no mesh imported')
        ok = False
    for ob in meshes:
        me = ob.data
        keys = [k.name for k in me.shape_keys.key_blocks] if me.shape_keys else []
        nodes = [n.type for m in me.materials if m and m.use_nodes for n in m.node_tree.nodes]
        print(f'{path}: mesh {ob.name}: {len(me.vertices)} vertices, {len(me.polygons)} faces, '
              f'shape keys {keys}, uv layers {[u.name for u in me.uv_layers]}, '
              f'normal map {"yes" if "NORMAL_MAP" in nodes and "TEX_IMAGE" in nodes else "no"}, '
              f'actions {[a.name for a in bpy.data.actions]}')
sys.exit(0 if ok else 1)
