"""Pieces of TOML scene files shared by the scene-reader tests (test_scene_reader.py,
test_fuzz_readers.py)."""

# Three bodies, one of each kind: "beam" (3 modes of the body file body/body.h5 beside
# the scene file, frame fixed at the origin), the rigid "block" and the point mass "bob".
BODIES = """\
[[body]]
name = "beam"
kind = "flexible"
source = "body/body.h5"
modes = 3
frame = "fixed"
position = [0.0, 0.0, 0.0]
q_f = [0.0, 0.0, 0.0]
modal_velocities = [0.0, 0.0, 0.0]
rayleigh = [0.0, 1e-4]

[[body]]
name = "block"
kind = "rigid"
mass = 1.0
inertia = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]]
position = [0.1, 0.2, 0.0]
velocity = [0.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 0.0]

[[body]]
name = "bob"
kind = "point_mass"
mass = 0.5
position = [0.1, 0.06, 0.025]
velocity = [0.0, -0.1, 0.0]
"""
