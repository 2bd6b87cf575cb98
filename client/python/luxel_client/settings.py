"""Maps Python keyword arguments onto luxel.v1.BakeSettings.

Every field of BakeSettings is accepted by its proto name (resolution,
samples_per_texel, time_budget_s, max_bounces, ...; see proto/luxel/v1/luxel.proto
for units), so fields added to the proto later work without a client change.
What each setting means, its default, range and units come from the settings
schema the build writes beside the generated stubs (``settings_schema.json``,
the output of ``luxel settings --json``): see ``SCHEMA``, ``defaults()`` and
``describe()``. Nothing here repeats a default or a range; the daemon
validates and names the field (``settings.max_bounces: must be in [0, 64],
got 99``) exactly as the CLI does.

Conveniences on top of the plain values:

- enums take their short name, any case: ``filter="gaussian"``,
  ``snapshot_format="exr"``, ``solver="progressive-nn"`` (or the full name, or
  the number);
- repeated enums take a list of those, or one comma-separated string:
  ``encodings="sh2,sg12"`` (``encoding=`` is accepted too, the field's name
  before it was typed);
- ``sky`` takes a dict (``{"color": (r, g, b), "intensity": 1.0}``; a colour
  alone implies KIND_CONSTANT) or a 3-sequence of linear RGB radiance;
- ``sun`` takes a dict with direction, color, illuminance, angular_radius_degrees;
- ``placements`` (client-dictated lightmap placement per node) takes a list of
  dicts: ``[{"node": 0, "scale_offset": (sx, sy, ox, oy), "page": 0}, ...]``
  (``instance`` selects an EXT_mesh_gpu_instancing element);
- a message field also takes the message itself.
"""

import json
import pathlib

from google.protobuf import descriptor as _descriptor

from ._stubs import luxel_pb2
from .errors import LuxelError

_FD = _descriptor.FieldDescriptor
# Keyword names of fields that were renamed when they became typed.
_RENAMED = {"encoding": "encodings"}


def _load_schema():
    """The settings schema written by the build beside luxel_pb2.py, as a dict
    name -> entry; empty when that file is missing (an older build)."""
    path = pathlib.Path(luxel_pb2.__file__).with_name("settings_schema.json")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {entry["name"]: entry for entry in doc.get("settings", [])}


# name ("max_bounces", "sky.color") -> {"type", "units", "help", "flag",
# "default", "range", "scope", "api_zero", "api_note", "min", "max", "choices"}
SCHEMA = _load_schema()


def defaults(api_only=True):
    """Default of every setting by name (``{"max_bounces": 4, ...}``); with
    api_only, only the settings the daemon API carries."""
    return {name: e["default"] for name, e in SCHEMA.items()
            if not api_only or e["scope"] != "local_only"}


def describe(name):
    """One line about a setting: help, units, default and range."""
    e = SCHEMA.get(name)
    if e is None:
        raise LuxelError("INVALID_ARGUMENT", f"settings.{name}: unknown setting", local=True)
    units = f" [{e['units']}]" if e["units"] else ""
    return f"settings.{name}: {e['help']}{units}; default {e['default']!r}; {e['range']}"


def _enum_prefix(enum_descriptor):
    zero = enum_descriptor.values_by_number[0].name
    return zero[:zero.rfind("_") + 1]


def enum_value(enum_descriptor, value, where):
    """Number of an enum value given as a number, a full name or a short name
    ("gaussian" for FILTER_GAUSSIAN)."""
    if isinstance(value, int):
        if value not in enum_descriptor.values_by_number:
            raise LuxelError("INVALID_ARGUMENT", f"{where}: no value {value} in {enum_descriptor.name}", True)
        return value
    wanted = str(value).upper().replace("-", "_")
    prefix = _enum_prefix(enum_descriptor)
    for candidate in enum_descriptor.values:
        if candidate.name in (wanted, prefix + wanted):
            return candidate.number
    names = ", ".join(v.name for v in enum_descriptor.values)
    raise LuxelError("INVALID_ARGUMENT", f"{where}: '{value}' is not one of {names}", local=True)


def _fill(message, values, prefix):
    """Sets the fields of ``message`` from a dict, naming bad fields as
    "<prefix>.<field>" the way the daemon does."""
    fields = message.DESCRIPTOR.fields_by_name
    for name, value in values.items():
        if prefix == "settings":
            name = _RENAMED.get(name, name)
        where = f"{prefix}.{name}"
        field = fields.get(name)
        path = where.split(".", 1)[1]
        if field is None and SCHEMA.get(path, {}).get("scope") == "local_only":
            raise LuxelError("INVALID_ARGUMENT", f"{where}: only in-process (luxel bake --local "
                             f"{SCHEMA[path]['flag']}); the daemon API has no such setting", local=True)
        if field is None:
            raise LuxelError("INVALID_ARGUMENT",
                             f"{where}: unknown setting (known: {', '.join(sorted(fields))})", local=True)
        if value is None:
            continue
        try:
            _set_field(message, field, value, where)
        except (TypeError, ValueError) as e:
            raise LuxelError("INVALID_ARGUMENT", f"{where}: {e}", local=True) from e


def _set_field(message, field, value, where):
    if field.label == _FD.LABEL_REPEATED:
        container = getattr(message, field.name)
        del container[:]
        if field.type == _FD.TYPE_MESSAGE:
            # A list of messages or dicts, each named by its index in errors.
            for i, item in enumerate(value):
                target = container.add()
                if isinstance(item, type(target)):
                    target.CopyFrom(item)
                else:
                    _fill(target, dict(item), f"{where}[{i}]")
            return
        if field.type == _FD.TYPE_ENUM:
            items = value.split(",") if isinstance(value, str) else value
            value = [enum_value(field.enum_type, v.strip() if isinstance(v, str) else v, where)
                     for v in items if v != ""]
        container.extend(value)
    elif field.type == _FD.TYPE_MESSAGE:
        target = getattr(message, field.name)
        if isinstance(value, type(target)):
            target.CopyFrom(value)
        elif field.message_type.name == "Sky" and not isinstance(value, dict):
            _fill(target, {"kind": "constant", "color": list(value)}, where)
        else:
            value = dict(value)
            if field.message_type.name == "Sky" and "kind" not in value and value.get("color"):
                value["kind"] = "constant"
            _fill(target, value, where)
            # An all-default sub-message must still count as given.
            target.SetInParent()
    elif field.type == _FD.TYPE_ENUM:
        setattr(message, field.name, enum_value(field.enum_type, value, where))
    else:
        setattr(message, field.name, value)


def make_settings(**settings):
    """A luxel.v1.BakeSettings from keyword arguments; see the module doc."""
    message = luxel_pb2.BakeSettings()
    _fill(message, settings, "settings")
    return message


def state_value(state):
    """A BakeState number from a number, "SUCCEEDED" or "BAKE_STATE_SUCCEEDED"."""
    return enum_value(luxel_pb2.BakeState.DESCRIPTOR, state, "states")


def state_name(state):
    """Short name of a BakeState number: 3 -> "SUCCEEDED"."""
    return luxel_pb2.BakeState.Name(state).removeprefix("BAKE_STATE_")
