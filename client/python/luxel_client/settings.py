"""Maps Python keyword arguments onto luxel.v1.BakeSettings.

Every field of BakeSettings is accepted by its proto name (resolution,
samples_per_texel, time_budget_s, max_bounces, ...; see proto/luxel/v1/luxel.proto
for units), so fields added to the proto later work without a client change.
Conveniences on top of the plain values:

- enums take their short name, any case: ``filter="gaussian"``,
  ``snapshot_format="exr"`` (or the full name, or the number);
- ``sky`` takes a dict (``{"color": (r, g, b), "intensity": 1.0}``; a colour
  alone implies KIND_CONSTANT) or a 3-sequence of linear RGB radiance;
- ``sun`` takes a dict with direction, color, illuminance, angular_radius_degrees;
- a message field also takes the message itself.
"""

from google.protobuf import descriptor as _descriptor

from ._stubs import luxel_pb2
from .errors import LuxelError

_FD = _descriptor.FieldDescriptor


def enum_value(enum_descriptor, value, where):
    """Number of an enum value given as a number, a full name or a short name
    ("gaussian" for FILTER_GAUSSIAN)."""
    if isinstance(value, int):
        if value not in enum_descriptor.values_by_number:
            raise LuxelError("INVALID_ARGUMENT", f"{where}: no value {value} in {enum_descriptor.name}", True)
        return value
    wanted = str(value).upper()
    for candidate in enum_descriptor.values:
        if wanted == candidate.name or candidate.name.endswith("_" + wanted):
            return candidate.number
    names = ", ".join(v.name for v in enum_descriptor.values)
    raise LuxelError("INVALID_ARGUMENT", f"{where}: '{value}' is not one of {names}", local=True)


def _fill(message, values, prefix):
    """Sets the fields of ``message`` from a dict, naming bad fields as
    "<prefix>.<field>" the way the daemon does."""
    fields = message.DESCRIPTOR.fields_by_name
    for name, value in values.items():
        where = f"{prefix}.{name}"
        field = fields.get(name)
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
