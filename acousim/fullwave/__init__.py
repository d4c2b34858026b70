"""Full-wave (boundary-element) scattering model of the cube dimer (PHYSICS.md section 7)."""
