"""
A rotating beam: geometric stiffening
=====================================

Linear FFR keeps the stiffness of the body at rest. A body that spins is stressed by its
own inertia, and that stress stiffens it; once the spin nears the first bending
frequency, linear FFR is wrong and then unstable. The spin-up beam of Kane, Ryan &
Banerjee (1987): a 10 m cantilever (EI = 1.4e4 N m², EA = 2.8e7 N, ρA = 1.2 kg/m) as a
tet10 solid (``validation/scenes/spin_up.py``), its hub spun up smoothly to 6 rad/s in
15 s. The body is preprocessed with its geometric stiffness
(``build_body(..., geometric_stiffness=True)``, ``ffrmbs preprocess --geometric-stiffness``)
and the FFR body switches the stiffening on (``geometric_stiffening=True``, in a scene file
``geometric_stiffening = true``).

Checks: with the stiffening, the tip lags by about the quasi-static deflection of the
largest angular acceleration, 11 ρA θ̈ₘₐₓ L⁵ / (120 EI) with θ̈ₘₐₓ = 2Ω/T, and settles
after the spin-up; without it, the hub's spin passes the first bending frequency
(3.80 rad/s, at t ≈ 8.5 s) and the tip runs away.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from validation.scenes.spin_up import RAMP_TIME, SPIN, T_END, beam_body, spin_up_system

data = beam_body(n_modes=10)          # tet10, 40 elements along x, with the geometric stiffness


def run(stiffening, t_end):
    """The tip's transverse displacement in the hub frame [m], every 0.05 s."""
    system, beam, v_tip = spin_up_system(data, geometric_stiffening=stiffening)
    result = system.simulate(t_end=t_end, dt=4e-3, integrator="moreau",
                             t_out=np.linspace(0.0, t_end, round(t_end / 0.05) + 1), outputs={"v_tip": v_tip})
    print(f"stiffening {'on ' if stiffening else 'off'}: {result.stats['steps']} steps, "
          f"{result.stats['cpu_s']:.2f} s CPU")
    return result.t, np.asarray(result["v_tip"], dtype=float).ravel()


# %%
# With and without the stiffening
# -------------------------------
t, v = run(True, T_END)
with warnings.catch_warnings(record=True) as caught:       # the spin monitor's advice, printed below
    warnings.simplefilter("always")
    t_lin, v_lin = run(False, 9.5)
print(f"warning: {caught[0].message}")
rho_a, ei, length = 1.2, 1.4e4, 10.0
quasi_static = 11 * rho_a * (2 * SPIN / RAMP_TIME) * length ** 5 / (120 * ei)
k = int(np.argmax(np.abs(v)))
print(f"stiffened: largest lag {v[k]:.3f} m at t = {t[k]:.2f} s (quasi-static estimate {quasi_static:.3f} m), "
      f"{v[-1] * 1e3:.2f} mm at t = {T_END:g} s")
print(f"linear FFR: {v_lin[-1]:.3g} m at t = {t_lin[-1]:g} s")
assert 0.8 < abs(v[k]) / quasi_static < 1.05
assert np.abs(v[t > 17.0]).max() < 0.01
assert np.abs(v_lin).max() > 2.0
assert "turn on geometric_stiffening" in str(caught[0].message)

fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(t, v, label="geometric stiffening")
ax.plot(t_lin, v_lin, label="linear FFR")
ax.axhline(-quasi_static, color="0.5", linestyle="--", label="quasi-static lag at θ̈ₘₐₓ")
ax.set_ylim(-1.5, 1.0)
ax.set_xlabel("t [s]")
ax.set_ylabel("tip displacement in the hub frame [m]")
ax.legend()
fig.tight_layout()
