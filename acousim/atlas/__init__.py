"""The attractor maps of the full-wave dimer: the atlas of field drops and the held-y map, with their figures."""
