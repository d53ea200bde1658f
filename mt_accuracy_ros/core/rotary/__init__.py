"""Rotary axes: calibration of their errors with a ball bar and with a touch probe.

``ballbar``   Zhu ch. 5: the telescopic magnetic ball bar on a rotary table,
              forward model (Zhu eqs. 5.1-5.13), the two-setup method that cancels
              the eccentricity (Zhu eqs. 5.14-5.16, 5.19-5.20), l2 and l-infinity
              estimation (Zhu eqs. 5.17-5.18).
``probing``   a calibration sphere probed at several rotary positions: sphere
              centres from touch points, and the rotary axes' location errors
              (Khan & Chen's position-independent errors) with the sphere's
              setup position separated out.
"""
