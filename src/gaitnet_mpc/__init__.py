"""gaitnet-mpc: variable-frequency humanoid walking over discrete terrain.

Implements the Gait-Net-augmented implicit kino-dynamic MPC of Li, Duan, Ma and
Nguyen, with its baselines, on MuJoCo models of a 24-DoF humanoid and a planar
five-link biped.
"""

__version__ = "0.1.0"
