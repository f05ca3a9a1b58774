"""Contact kinematics, hierarchical search, force laws and solvers (issue 6)."""
