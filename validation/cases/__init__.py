"""Validation cases; each module defines NAME (= module name), DESCRIPTION and run(quick)."""

CASE_MODULES = ["cantilever", "complex_beam", "ffr_frequencies", "ffr_free_flight", "ffr_inertia",
                "ffr_spinning_free", "wobble_step", "wobble_energy", "wobble_shear", "wobble_effective_mass",
                "wobble_rotation", "wobble_complex", "wobble_case_study", "wobble_decoupling",
                "wobble_boundary", "contact_bounce", "contact_friction", "contact_point_mass_beam",
                "contact_sliding_ball", "contact_unstructured", "contact_hole", "contact_full_fe", "contact_face_impact",
                "contour_fit_geometry", "contour_fit_cost",
                "spin_up_beam"]
