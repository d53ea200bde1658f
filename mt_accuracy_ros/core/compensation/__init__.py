"""Volumetric compensation: the error model the nodes run and what a CNC takes.

* ``error_model``  the kinematic chain plus the effects the model includes
                   (thermal drift, squareness, ...), evaluated at the TCP.
* ``tables``       per-axis compensation tables in ISO 230-1 names, as CNC
                   volumetric-compensation packages read them.

Command compensation p2 = p1 - delta e follows Kidani eqs. 3.14-3.16.
"""
