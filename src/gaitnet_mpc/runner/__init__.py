"""The closed loop: a controller and the simulator run together for one episode."""
