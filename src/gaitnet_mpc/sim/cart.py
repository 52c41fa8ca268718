"""A cart the robot pushes with its hands (Fig. 10): scene geometry and its read-out.

The cart is one MuJoCo body on a slide joint along the world x axis, at a fixed height
(its wheels are drawn, not simulated). Its mass is the cart's own plus a load that no
controller is told about. Rolling resistance is Coulomb friction on the slide joint,
``c_rr (m_cart + m_load) g``, plus a small viscous term.

The hands push on a vertical plate at the cart's rear: each forearm's capsule and the plate
form a frictionless contact pair (MuJoCo ``condim = 1``), so the cart can only push back
along the plate's normal, never pull, lift or hold the robot up. The robot's legs collide
with the cart's body as they would with any obstacle (its geom's ``conaffinity`` matches
the robot geoms' ``contype``); the terrain does not touch the cart.
"""

from __future__ import annotations

from dataclasses import dataclass

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.errors import ConfigError

#: Gravity used for the rolling-resistance force [m/s^2].
_G_MPS2 = 9.81
#: Largest cart load accepted [kg] (:attr:`Cart.load_kg`'s range): 10x the paper's 35 kg.
MAX_CART_LOAD_KG = 350.0

#: Half sizes of the push plate (x thickness, y width, z height) and of the cart's body [m].
_PLATE_HALF_M = (0.01, 0.30, 0.16)  # a 0.6 m wide handle plate
_BODY_HALF_M = (0.30, 0.22, 0.12)
_WHEEL_RADIUS_M = 0.06


@dataclass(frozen=True)
class Cart:
    """A cart on a straight rail along +x, ahead of the robot's start.

    Attributes:
        load_kg: mass on the cart that no controller is told about [kg] (Fig. 10: 35 kg).
        cart_mass_kg: the empty cart's mass [kg].
        rolling_resistance: rolling-resistance coefficient c_rr [-] (hard wheels on a hard
            floor: 0.005-0.02).
        damping_ns_per_m: viscous resistance of the rail [N s/m].
        plate_ahead_m: x distance from the robot's start position (its trunk) to the push
            plate's rear face [m]; the hands of the pushing pose reach about 0.32 m ahead
            of the trunk, so the default leaves a 5 cm gap the robot closes by walking.
        plate_height_m: height of the plate's centre above the start ground [m] (the
            humanoid's shoulders stand at about 0.7 m).
    """

    load_kg: float = bounded(35.0, "[0, 350] kg", "a load", "10x the paper's 35 kg")
    cart_mass_kg: float = bounded(5.0, "[0.5, 100] kg", "a mass", "a hand cart's")
    rolling_resistance: float = bounded(0.01, "[0, 0.5]", "a coefficient", "wheels, not skids")
    damping_ns_per_m: float = bounded(2.0, "[0, 1000] N s/m", "a damping", "a rail's")
    plate_ahead_m: float = bounded(0.37, "[0.2, 2] m", "a distance", "beyond the feet's reach")
    plate_height_m: float = bounded(0.68, "[0.2, 1.5] m", "a height", "within the arms' reach")

    def __post_init__(self) -> None:
        try:
            check_ranges(self)
        except ConfigError as exc:
            raise ConfigError(f"cart.{exc.field}", exc.value, exc.expected) from None

    @property
    def mass_kg(self) -> float:
        """Cart plus load [kg]."""
        return self.cart_mass_kg + self.load_kg

    @property
    def resistance_n(self) -> float:
        """Coulomb rolling resistance ``c_rr m g`` [N]."""
        return self.rolling_resistance * self.mass_kg * _G_MPS2

    def to_dict(self) -> dict[str, float]:
        return {
            "load_kg": self.load_kg,
            "cart_mass_kg": self.cart_mass_kg,
            "rolling_resistance": self.rolling_resistance,
            "damping_ns_per_m": self.damping_ns_per_m,
            "plate_ahead_m": self.plate_ahead_m,
            "plate_height_m": self.plate_height_m,
        }


#: Name of the cart's body, its slide joint and its push plate in the scene.
CART_BODY, CART_JOINT, CART_PLATE = "cart", "cart_slide", "cart_plate"


def cart_xml(
    cart: Cart, start_xyz_m: tuple[float, float, float], hand_geoms: tuple[str, ...]
) -> tuple[str, str]:
    """The cart's ``<body>`` (for the worldbody) and its ``<contact>`` section.

    Args:
        cart: the cart.
        start_xyz_m: the robot's start position on the ground (x, y, ground height) [m].
        hand_geoms: the robot geoms that push on the plate (the forearms).
    """
    x0, y0, z0 = start_xyz_m
    px, py, pz = _PLATE_HALF_M
    bx, by, bz = _BODY_HALF_M
    plate_x = x0 + cart.plate_ahead_m + px
    z_body = z0 + _WHEEL_RADIUS_M + 0.06 + bz
    z_plate = z0 + cart.plate_height_m
    wheels = "".join(
        f'<geom type="cylinder" size="{_WHEEL_RADIUS_M} 0.015" zaxis="0 1 0" '
        f'pos="{sx * (bx - 0.08):.3f} {sy * (by - 0.02):.3f} {z0 + _WHEEL_RADIUS_M:.3f}" '
        'contype="0" conaffinity="0" mass="0" rgba="0.1 0.1 0.1 1"/>'
        for sx in (-1, 1)
        for sy in (-1, 1)
    )
    body = f"""
    <body name="{CART_BODY}" pos="{plate_x:.4f} {y0:.4f} 0">
      <joint name="{CART_JOINT}" type="slide" axis="1 0 0"
             frictionloss="{cart.resistance_n:.6g}" damping="{cart.damping_ns_per_m:.6g}"/>
      <inertial pos="{px + bx:.4f} 0 {z_body:.4f}" mass="{cart.mass_kg:.6g}"
                diaginertia="1 1 1"/>
      <geom name="{CART_PLATE}" type="box" size="{px} {py} {pz}"
            pos="0 0 {z_plate:.4f}" contype="0" conaffinity="0"
            rgba="0.8 0.45 0.1 1"/>
      <geom name="cart_body" type="box" size="{bx} {by} {bz}"
            pos="{px + bx:.4f} 0 {z_body:.4f}" contype="0" conaffinity="2"
            rgba="0.55 0.35 0.2 1"/>
      <geom name="cart_post" type="box" size="0.01 0.02 {(z_plate - z_body) / 2:.4f}"
            pos="{px:.4f} 0 {(z_plate + z_body) / 2:.4f}" contype="0"
            conaffinity="0" rgba="0.3 0.3 0.3 1"/>
      {wheels}
    </body>
"""
    pairs = "".join(f'<pair geom1="{g}" geom2="{CART_PLATE}" condim="1"/>' for g in hand_geoms)
    return body, f"<contact>{pairs}</contact>"
