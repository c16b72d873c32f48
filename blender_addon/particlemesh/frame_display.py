"""Showing a live object's cached frames in the viewport without Blender evaluating them again.

Swapping an object's mesh makes Blender evaluate the object anew: copy the mesh, compute its
normals and, with custom split normals, its loop-normal spaces (0.35 s for 1.5M triangles
with Blender's own normals, 1.1 s with custom normals; bench/RESULTS.md), and so does pointing
a Geometry Nodes Object Info at another object. An object hidden in the viewport with the eye
(hide_set) stays in the depsgraph with its evaluated mesh, and showing it again evaluates
nothing (a base flag). So each frame the live cache keeps as a mesh gets a *holder*: a child
of the generated object (it follows its transform), unselectable, unrendered, whose mesh is
that frame's mesh; the current frame's holder is the one not hidden. While holders show its
frames, the generated object itself shows nothing in the viewport, through a viewport-only
Geometry Nodes modifier with an empty output (select it in the Outliner, where its holders
sit under it).

Used only where it shows the same thing as the object's own mesh would: no other modifier on
the object, no material linked to the object, not in edit mode, no other data using the object
(an emitter, a modifier's target); elsewhere the mesh is swapped as before. Renders never see holders (hidden in renders, the modifier off in renders: the
render handler writes the object's own mesh). Holders and the modifier are never saved: before
a save (and when live mode stops, the cache is cleared or a bake begins) the shown mesh becomes
the object's own mesh again and they are removed.

Python references to IDs do not survive undo: everything here is found by name and checked by
the tag the live cache gave the frame (live.FRAME_TAG on the holder and on its mesh)."""

import bpy

#: The viewport-only modifier that hides the object's own mesh while a holder shows its frame,
#: and its node group (nothing linked to the output: empty geometry).
MODIFIER = "particlemesh frame"
NODE_GROUP = "particlemesh frame display"
#: The custom property that marks a holder object (its value: the frame's tag).
HOLDER_TAG = "particlemesh_live_holder"
#: On the generated object: the tag of the holder it shows (stored in the file's data, so
#: that undo restores it with the holders).
SHOWN_TAG = "particlemesh_live_shown"


def usable(obj):
    """Whether the display shows exactly what the object's own mesh would, to the viewport
    and to anything that reads the object's evaluated geometry (nothing else may use it: a
    particle system emitting from it, another object's modifier or constraint aiming at it
    would see the emptied mesh)."""
    return (obj.mode != "EDIT"
            and all(m.name == MODIFIER for m in obj.modifiers)
            and all(slot.link == "DATA" for slot in obj.material_slots)
            and not _used_by_others(obj))


def _used_by_others(obj):
    users = bpy.data.user_map(subset=[obj]).get(obj, ())
    return any(not isinstance(user, (bpy.types.Collection, bpy.types.Scene))
               and not (isinstance(user, bpy.types.Object) and HOLDER_TAG in user)
               for user in users)


def _node_group():
    group = bpy.data.node_groups.get(NODE_GROUP)
    if group is not None and group.bl_idname == "GeometryNodeTree":
        return group
    group = bpy.data.node_groups.new(NODE_GROUP, "GeometryNodeTree")
    if hasattr(group, "interface"):  # Blender 4.0+
        group.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        group.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        group.inputs.new("NodeSocketGeometry", "Geometry")
        group.outputs.new("NodeSocketGeometry", "Geometry")
    group.nodes.new("NodeGroupInput")
    group.nodes.new("NodeGroupOutput")  # its Geometry unlinked: empty
    return group


def _modifier(obj):
    modifier = obj.modifiers.get(MODIFIER)
    return modifier if modifier is not None and modifier.type == "NODES" else None


def shown_holder(obj):
    """The holder the object's display shows now, or None (the object shows its own mesh)."""
    modifier = _modifier(obj)
    tag = obj.get(SHOWN_TAG)
    if modifier is None or not modifier.show_viewport or tag is None:
        return None
    return next((child for child in obj.children if child.get(HOLDER_TAG) == tag), None)


def shown_mesh(obj):
    """The mesh the viewport shows for `obj`: its current frame's holder's, else its own."""
    holder = shown_holder(obj)
    return holder.data if holder is not None else obj.data


def _holder(obj, mesh, tag):
    """The holder of `mesh` (the frame tagged `tag`), made if missing."""
    holder = find_holder(mesh.name, tag)
    if holder is not None and holder.data != mesh:
        bpy.data.objects.remove(holder)
        holder = None
    if holder is None:
        holder = bpy.data.objects.new(mesh.name, mesh)
        holder[HOLDER_TAG] = tag
        holder.hide_render = True
        holder.hide_select = True
        for collection in obj.users_collection:
            collection.objects.link(holder)
        if not holder.users_collection:
            bpy.context.scene.collection.objects.link(holder)
        _hide(holder, True)
    if holder.parent != obj:
        holder.parent = obj  # the mesh is in the object's space: the identity below it
        holder.matrix_parent_inverse.identity()
    return holder


#: The object's viewport display settings that its holders take on (a holder shows the frame
#: as the object would).
_DISPLAY = ("display_type", "show_wire", "show_all_edges", "show_in_front")


def _copy_display(obj, holder):
    for attribute in _DISPLAY:
        value = getattr(obj, attribute)
        if getattr(holder, attribute) != value:
            setattr(holder, attribute, value)
    if tuple(holder.color) != tuple(obj.color):
        holder.color = obj.color


def find_holder(name, tag):
    """The holder tagged `tag` (named `name` unless that name was taken), or None."""
    holder = bpy.data.objects.get(name)
    if holder is not None and holder.get(HOLDER_TAG) == tag:
        return holder
    return next((o for o in bpy.data.objects if o.get(HOLDER_TAG) == tag), None)


def _hide(holder, hide):
    """Hide or show in every view layer (the eye: a hidden object stays evaluated, unlike one
    disabled in viewports, and showing it again evaluates nothing)."""
    for scene in bpy.data.scenes:
        for view_layer in scene.view_layers:
            try:
                if holder.hide_get(view_layer=view_layer) != hide:
                    holder.hide_set(hide, view_layer=view_layer)
            except RuntimeError:  # not in that view layer's collections
                pass


def show(obj, mesh, tag):
    """Show `mesh` (a frame the cache keeps, tagged `tag`) on `obj` through its holder."""
    old = shown_holder(obj)
    holder = _holder(obj, mesh, tag)
    modifier = _modifier(obj)
    if modifier is None:
        modifier = obj.modifiers.new(MODIFIER, "NODES")
        modifier.node_group = _node_group()
        modifier.show_render = False
        modifier.show_in_editmode = False
    if not modifier.show_viewport:
        modifier.show_viewport = True
    if obj.get(SHOWN_TAG) != tag:
        obj[SHOWN_TAG] = tag
    _copy_display(obj, holder)
    _hide(holder, obj.hide_viewport or obj.hide_get())  # the object hidden: its frame too
    for child in obj.children:  # the one shown before, and any undo brought back unhidden
        if child != holder and HOLDER_TAG in child:
            _hide(child, True)
    return old


def hide(obj):
    """Let the object show its own mesh (before writing it in place); holders stay."""
    modifier = _modifier(obj)
    if modifier is not None and modifier.show_viewport:
        holder = shown_holder(obj)
        if holder is not None:
            _hide(holder, True)
        modifier.show_viewport = False


def stop(obj):
    """Make the shown mesh the object's own again and remove its modifier (holders are removed
    by remove_holder once nothing shows them). Returns whether there was a modifier."""
    modifier = _modifier(obj)
    if modifier is None:
        return False
    holder = shown_holder(obj)
    if holder is not None:
        _hide(holder, True)
        if obj.data != holder.data:
            obj.data = holder.data
    obj.modifiers.remove(modifier)
    if SHOWN_TAG in obj:
        del obj[SHOWN_TAG]
    return True


def remove_holder(name, tag):
    """Delete the holder of the kept mesh `name` tagged `tag`, unless an object shows it."""
    holder = find_holder(name, tag)
    if holder is None or _shown_by_any(holder):
        return False
    bpy.data.objects.remove(holder)
    return True


def _shown_by_any(holder):
    return any(shown_holder(obj) == holder for obj in bpy.data.objects
               if obj.type == "MESH" and MODIFIER in obj.modifiers)


def sweep(held_tags):
    """Remove holders whose frame the cache no longer keeps and that nothing shows (undo can
    bring back holders the cache had already let go)."""
    shown = {shown_holder(obj) for obj in bpy.data.objects
             if obj.type == "MESH" and MODIFIER in obj.modifiers}
    for holder in [o for o in bpy.data.objects if HOLDER_TAG in o]:
        if holder not in shown and holder[HOLDER_TAG] not in held_tags:
            bpy.data.objects.remove(holder)


def stop_all():
    """Every object back to its own mesh; every holder, modifier and the node group gone."""
    for obj in [o for o in bpy.data.objects if o.type == "MESH" and MODIFIER in o.modifiers]:
        stop(obj)
    for holder in [o for o in bpy.data.objects if HOLDER_TAG in o]:
        bpy.data.objects.remove(holder)
    group = bpy.data.node_groups.get(NODE_GROUP)
    if group is not None and group.users == 0:
        bpy.data.node_groups.remove(group)
