"""The 3D View sidebar panel (N panel, "Particlemesh" tab)."""

import bpy

from . import generate, live
from .operators import draw_method_settings


class _Panel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Particlemesh"


class _ObjectSubPanel(_Panel):
    """A part of the Generated Mesh panel, shown when that panel is."""
    bl_parent_id = "VIEW3D_PT_particlemesh_object"

    @classmethod
    def poll(cls, context):
        return VIEW3D_PT_particlemesh_object.poll(context)


def _draw_settings(layout, context, which):
    """The active object's viewport or render ("which") settings of its method."""
    state = context.active_object.particlemesh
    layout.use_property_split = True
    draw_method_settings(layout, getattr(state, which), state.method)


class VIEW3D_PT_particlemesh(_Panel, bpy.types.Panel):
    bl_label = "Particlemesh"

    def draw(self, context):
        layout = self.layout
        ok, info = generate.library_status()
        if not ok:
            box = layout.box()
            box.alert = True
            for line in _wrap(info, 40):
                box.label(text=line)
        col = layout.column(align=True)
        col.enabled = ok
        col.operator("particlemesh.triangulate", icon="MESH_ICOSPHERE")
        col.operator("particlemesh.polygonize", icon="META_BALL")
        col.operator("particlemesh.smooth", icon="MOD_SUBSURF")
        layout.operator("particlemesh.import_cloud", icon="IMPORT")


class VIEW3D_PT_particlemesh_object(_Panel, bpy.types.Panel):
    bl_label = "Generated Mesh"
    bl_parent_id = "VIEW3D_PT_particlemesh"

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and obj.particlemesh.is_generated

    def draw(self, context):
        obj = context.active_object
        state = obj.particlemesh
        layout = self.layout
        layout.use_property_split = True
        if state.source_kind == "FILES":
            layout.prop(state, "file_pattern")
            layout.prop(state, "frame_offset")
            layout.label(text=f"{state.method.title()} the particle files")
        else:
            layout.prop(state, "source")
            layout.label(text=f"{state.method.title()} the {state.source_kind.lower()}"
                              + (f" '{state.particle_system}'" if state.particle_system else ""))
        row = layout.row()
        row.enabled = not state.baked
        row.prop(state, "live")
        if state.method == "TRIANGULATE":
            row = layout.row()
            row.active = state.live and not state.baked
            row.prop(state, "viewport_budget")
        row = layout.row()
        row.active = state.live and not state.baked
        row.prop(state, "instant_frames")
        row = layout.row()
        row.active = state.live and not state.baked
        row.prop(state, "finish_every_frame")
        layout.operator("particlemesh.update", icon="FILE_REFRESH")
        record = live.last_update.get(obj.name_full)
        if record:
            if "error" in record:
                box = layout.box()
                box.alert = True
                for line in _wrap(f"frame {record['frame']}: {record['error']}", 40):
                    box.label(text=line)
            else:
                layout.label(text=f"frame {record['frame']} ({record['mode'].lower()}): "
                                  f"{1000 * record['seconds']:.0f} ms"
                                  + (", cached" if record.get("cached") else "")
                                  + (", finished at rest" if record.get("unfinished") else ""))
                meshed, read = record.get("vertices"), record.get("particles")
                if state.method == "TRIANGULATE" and meshed and read and meshed < read:
                    factor = record.get("thin")
                    how = f"Thin Out {factor:.2f}" if factor else "Thin Out"
                    layout.label(text=f"{meshed} of {read} particles meshed ({how})")
        entries, size = live.cache_info(obj)
        row = layout.row()
        row.label(text=f"cache: {entries} frames, {size / 2**20:.1f} MB")
        row.operator("particlemesh.clear_cache", text="", icon="TRASH")


class VIEW3D_PT_particlemesh_viewport(_ObjectSubPanel, bpy.types.Panel):
    bl_label = "Viewport Settings"

    def draw(self, context):
        _draw_settings(self.layout, context, "viewport")


class VIEW3D_PT_particlemesh_render(_ObjectSubPanel, bpy.types.Panel):
    bl_label = "Render Settings"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.active_object.particlemesh, "use_render_settings", text="")

    def draw(self, context):
        self.layout.active = context.active_object.particlemesh.use_render_settings
        _draw_settings(self.layout, context, "render")


class VIEW3D_PT_particlemesh_bake(_ObjectSubPanel, bpy.types.Panel):
    bl_label = "Bake"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        state = context.active_object.particlemesh
        layout = self.layout
        if state.baked:
            layout.label(text=f"baked frames {state.bake_start}..{state.bake_end}", icon="CHECKMARK")
            layout.operator("particlemesh.free_bake", icon="TRASH")
        else:
            layout.operator("particlemesh.bake", icon="RENDER_ANIMATION")


def _wrap(text, width):
    words, line, lines = text.split(), "", []
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    if line:
        lines.append(line)
    return lines


classes = (
    VIEW3D_PT_particlemesh,
    VIEW3D_PT_particlemesh_object,
    VIEW3D_PT_particlemesh_viewport,
    VIEW3D_PT_particlemesh_render,
    VIEW3D_PT_particlemesh_bake,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
