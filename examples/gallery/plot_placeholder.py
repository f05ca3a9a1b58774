"""
Placeholder
===========

A tiny script that only proves the gallery runs at build time (the guide helper's
scripts replace it at merge).
"""
import matplotlib.pyplot as plt

plt.plot([0.0, 1.0], [0.0, 1.0])
plt.show()
