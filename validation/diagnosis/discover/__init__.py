"""Step 3, discover: the library terms that carry what no candidate explains.

* :mod:`~validation.diagnosis.discover.library_terms`: the discovered terms and the energy-balance form of the
  dissipations;
* :mod:`~validation.diagnosis.discover.joint_model`: the identified candidates judged against the discovered terms, and
  the final joint model of the identified effects with them.
"""
