"""What one row of the Gait-Net data set holds: one step start, its features and its dt.

The 16 features (paper Sec. V-B: CoM position, CoM velocity, trunk Euler angles, trunk
angular velocity, foot locations of both legs) are taken at the step start, in the
**heading frame** (x along the commanded heading, y to its left, z up; the protocol
commands no turning, so it is the world frame rotated by the initial heading):

* ``com_{x,y}_m``: CoM relative to the stance foot, ``com_z_m``: CoM height above it.
  The paper's world-frame CoM position grows with the distance walked, so a network
  would learn the course length; relative to the stance foot it does not.
* ``com_v{x,y,z}_mps``: CoM velocity.
* ``roll_rad``, ``pitch_rad``, ``yaw_rad``: trunk ZYX Euler angles, yaw from the heading.
* ``w{x,y,z}_radps``: trunk angular velocity (world axes, in the heading frame).
* ``{left,right}_foot_{x,y}_m``: each foot's horizontal position relative to the CoM:
  the stance foot where it stands, the swing foot where the teacher actually put it down
  (its position at the next step start). Indexed by leg, not by role, as in the paper
  (its Fig. 4 finds both legs weighted equally with opposite signs). The stance foot's
  pair is minus ``com_{x,y}_m``: the feature set carries that redundancy on purpose, to
  keep the paper's 16 and let the feature selection of Gait-Net find it.

The label is ``dt_s``, the step's MPC sampling time (duration over ``h'`` stages). The
other columns (set, time, command, pushes, world-frame positions) serve later analysis.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

SCHEMA_VERSION = 1


@dataclass(frozen=True)
class Column:
    """A column: name, Arrow type name, unit ("" for none), meaning and a sane range."""

    name: str
    dtype: str  # "float64", "int32", "bool" or "string"
    unit: str
    description: str
    range: tuple[float, float] | None = None  # finite values outside are an error


_F = "float64"
_FOOT = "{} foot - CoM, heading {} (the touchdown while swinging)"
_W = (-1e4, 1e4)  # world coordinates [m]: finite is what matters
FEATURES: tuple[Column, ...] = (
    Column("com_x_m", _F, "m", "CoM - stance foot, heading x", (-1.0, 1.0)),
    Column("com_y_m", _F, "m", "CoM - stance foot, heading y", (-1.0, 1.0)),
    Column("com_z_m", _F, "m", "CoM height above the stance foot centre", (0.05, 2.0)),
    Column("com_vx_mps", _F, "m/s", "CoM velocity, heading x", (-5.0, 5.0)),
    Column("com_vy_mps", _F, "m/s", "CoM velocity, heading y", (-5.0, 5.0)),
    Column("com_vz_mps", _F, "m/s", "CoM velocity, z", (-5.0, 5.0)),
    Column("roll_rad", _F, "rad", "trunk roll (ZYX Euler)", (-3.1416, 3.1416)),
    Column("pitch_rad", _F, "rad", "trunk pitch (ZYX Euler)", (-3.1416, 3.1416)),
    Column("yaw_rad", _F, "rad", "trunk yaw - heading, wrapped", (-3.1416, 3.1416)),
    Column("wx_radps", _F, "rad/s", "trunk angular velocity, heading x", (-50.0, 50.0)),
    Column("wy_radps", _F, "rad/s", "trunk angular velocity, heading y", (-50.0, 50.0)),
    Column("wz_radps", _F, "rad/s", "trunk angular velocity, z", (-50.0, 50.0)),
    Column("left_foot_x_m", _F, "m", _FOOT.format("left", "x"), (-1, 1)),
    Column("left_foot_y_m", _F, "m", _FOOT.format("left", "y"), (-1, 1)),
    Column("right_foot_x_m", _F, "m", _FOOT.format("right", "x"), (-1, 1)),
    Column("right_foot_y_m", _F, "m", _FOOT.format("right", "y"), (-1, 1)),
)

LABEL = Column("dt_s", _F, "s", "the step's MPC sampling time (label)", (0.005, 0.5))

EXTRA: tuple[Column, ...] = (
    Column("set_id", "int32", "", "set index"),
    Column("segment", "int32", "", "episode within the set (a fall starts a new one)"),
    Column("step_index", "int32", "", "step number within the episode (0 = first)"),
    Column("t_s", _F, "s", "episode time of the step start", (0.0, 1e5)),
    Column("set_t_s", _F, "s", "set time of the step start", (0.0, 1e5)),
    Column("vx_cmd_mps", _F, "m/s", "the set's forward command", (-2.0, 2.0)),
    Column("step_duration_s", _F, "s", "measured time to the next step start", (0.005, 5.0)),
    Column("push_phase", "bool", "", "the step starts in the set's pushed half"),
    Column("pushed", "bool", "", "a push acted during the step"),
    Column("stance_foot", "string", "", "'left' or 'right'"),
    Column("heading_rad", _F, "rad", "heading of the frame above", (-3.1416, 3.1416)),
    Column("com_world_x_m", _F, "m", "CoM, world x", _W),
    Column("com_world_y_m", _F, "m", "CoM, world y", _W),
    Column("com_world_z_m", _F, "m", "CoM, world z", _W),
    Column("stance_world_x_m", _F, "m", "stance foot centre, world x", _W),
    Column("stance_world_y_m", _F, "m", "stance foot centre, world y", _W),
    Column("stance_world_z_m", _F, "m", "stance foot centre, world z", _W),
    Column("liftoff_world_x_m", _F, "m", "swing foot at the step start, world x", _W),
    Column("liftoff_world_y_m", _F, "m", "swing foot at the step start, world y", _W),
    Column(
        "touchdown_world_x_m", _F, "m", "swing foot at the next step start, world x", (-1e4, 1e4)
    ),
    Column(
        "touchdown_world_y_m", _F, "m", "swing foot at the next step start, world y", (-1e4, 1e4)
    ),
    Column(
        "touchdown_world_z_m", _F, "m", "swing foot at the next step start, world z", (-1e4, 1e4)
    ),
)

COLUMNS: tuple[Column, ...] = (*EXTRA, *FEATURES, LABEL)
FEATURE_NAMES: tuple[str, ...] = tuple(c.name for c in FEATURES)
COLUMN_BY_NAME: dict[str, Column] = {c.name: c for c in COLUMNS}


def arrow_schema() -> Any:
    """The pyarrow schema, with each field's unit and meaning as field metadata."""
    import pyarrow as pa

    types = {
        "float64": pa.float64(),
        "int32": pa.int32(),
        "bool": pa.bool_(),
        "string": pa.string(),
    }
    fields = [
        pa.field(
            c.name,
            types[c.dtype],
            nullable=False,
            metadata={"unit": c.unit, "description": c.description},
        )
        for c in COLUMNS
    ]
    return pa.schema(fields, metadata={"gaitnet_mpc.schema_version": str(SCHEMA_VERSION)})


def describe() -> list[dict[str, object]]:
    """The schema as the manifest writes it: one entry per column."""
    return [
        {
            "name": c.name,
            "dtype": c.dtype,
            "unit": c.unit,
            "description": c.description,
            "role": "feature" if c in FEATURES else "label" if c == LABEL else "info",
        }
        for c in COLUMNS
    ]
