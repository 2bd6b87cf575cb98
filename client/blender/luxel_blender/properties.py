"""Per-scene bake settings (scene.luxel). The names are `luxel bake`'s
options; everything else goes through "Extra arguments"."""

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty


class LuxelSceneSettings(bpy.types.PropertyGroup):
    resolution: IntProperty(name="Resolution", default=512, min=16, max=8192,
                            description="Lightmap side in texels (--resolution)")
    samples: IntProperty(name="Samples", default=256, min=1, max=1 << 20,
                         description="Paths per covered texel (--samples)")
    bounces: IntProperty(name="Bounces", default=4, min=0, max=64,
                         description="Indirect bounces (--bounces)")
    time_s: FloatProperty(name="Time limit", default=0.0, min=0.0, unit="TIME_ABSOLUTE",
                          description="Stop after this many seconds of tracing (0: no limit; --time)")
    snapshot_interval_s: FloatProperty(name="Snapshot interval", default=1.0, min=0.05,
                                       description="Seconds between progressive snapshots")
    selection_only: BoolProperty(name="Selected objects only", default=False,
                                 description="Export and bake only the selected objects")
    baked_only: BoolProperty(name="Show baked light only", default=True,
                             description="Materials show lightmap x base colour instead of live "
                                         "shading (their 'Luxel Mix' node's factor)")
    extra_args: StringProperty(name="Extra arguments", default="",
                               description="More `luxel bake` options, e.g. --sky 0,0,0 --denoise atrous")
