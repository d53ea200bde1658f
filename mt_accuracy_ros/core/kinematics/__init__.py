"""Rigid-body kinematics of a machine tool with its geometric errors.

* ``htm``              elementary homogeneous transformations (Kidani Table 2.1,
                       Khan & Chen eqs. 1-6).
* ``machine``          declarative machine descriptions (YAML), ISO 230-1 names.
* ``error_functions``  position-dependent error functions of an axis.
* ``chain``            the error chain to the TCP: tool and workpiece loops
                       (Kidani eqs. 2.3-2.14, Khan & Chen eqs. 7-17, Zhu App. A).
"""
