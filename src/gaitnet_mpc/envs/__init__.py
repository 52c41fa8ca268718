"""Environments for learning on top of the controller (optional extras).

* :mod:`gaitnet_mpc.envs.gym_env`: a Gymnasium environment whose action is each
  footstep's MPC sampling time (the Gait-Net decision); needs the ``gym`` extra
  (``pip install 'gaitnet-mpc[gym]'``).

Nothing is imported here, so ``import gaitnet_mpc.envs`` works without the extras.
"""
