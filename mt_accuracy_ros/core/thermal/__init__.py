"""Thermal behaviour of the machine and thermal error models.

* ``fem``               FE heat conduction with convection, thermal modes and
                        their time constants (Zhu eqs. 3.1-3.11, ch. 3).
* ``regression``        thermal error regression, lag features, time constants
                        (Zhu eqs. 3.12-3.17, Krulewich eq. 3).
* ``links``             thermal links of the kinematic chain (Zhu eq. 4.2, ch. 4).
* ``sensor_placement``  Gaussian-integration placement of thermocouples
                        (Krulewich eqs. 1-23).
"""
