"""Static force/torque sweeps of any static model over (theta, y), the static coefficients fitted to them, and their figures."""
