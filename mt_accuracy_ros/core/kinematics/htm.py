"""Homogeneous transformation matrices, batched over leading dimensions.

Elementary HTMs of Kidani Table 2.1 (= Khan & Chen eqs. 1-6): translations
D_X(x), D_Y(y), D_Z(z) and rotations D_A(alpha), D_B(beta), D_C(gamma) about
x, y, z. Six error motions (dx, dy, dz, ex, ey, ez) of a joint combine either
exactly, as the product D_X D_Y D_Z D_A D_B D_C (the left side of Kidani eq.
2.7), or to first order as the single matrix of Kidani eq. 2.7 / Khan & Chen
eq. 7.

Every function takes arrays of any shape ``S`` and returns ``S + (4, 4)``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def cross(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Cross products a x b of 3-vectors along the last axis, broadcast together.

    The component formula ``np.cross`` evaluates, the same numbers, without its
    axis bookkeeping: that cost more than the product itself on the few rows a node
    evaluates at every message.

    Parameters
    ----------
    a, b : array_like, shape S + (3,) (broadcast together)
        Vectors (any unit).

    Returns
    -------
    ndarray, shape S + (3,)
        a x b.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def identity(shape: tuple[int, ...] = ()) -> NDArray[np.float64]:
    """Identity HTMs of shape ``shape + (4, 4)``.

    Parameters
    ----------
    shape : tuple of int, optional
        Leading (batch) shape ``S``; ``()`` gives one 4x4 matrix.

    Returns
    -------
    ndarray, shape S + (4, 4)
        Identity homogeneous transformation matrices (dimensionless).
    """
    out = np.zeros(shape + (4, 4))
    out[..., [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    return out


def translation(dx: ArrayLike = 0.0, dy: ArrayLike = 0.0, dz: ArrayLike = 0.0) -> NDArray:
    """D_X(dx) D_Y(dy) D_Z(dz) (Kidani Table 2.1; Khan & Chen eqs. 1-3).

    Parameters
    ----------
    dx, dy, dz : array_like, shape S (broadcast together)
        Translations along x, y, z. Unit-agnostic: the HTM's translation column
        carries the unit given (the package uses [m]).

    Returns
    -------
    ndarray, shape S + (4, 4)
        Pure-translation HTMs.
    """
    dx, dy, dz = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (dx, dy, dz)))
    out = identity(dx.shape)
    out[..., 0, 3] = dx
    out[..., 1, 3] = dy
    out[..., 2, 3] = dz
    return out


def rotation(axis: str, angle: ArrayLike) -> NDArray:
    """D_A, D_B or D_C: rotation by ``angle`` [rad] about x, y or z (Kidani Table 2.1;
    Khan & Chen eqs. 4-6).

    Parameters
    ----------
    axis : {"x", "y", "z"}
        Axis of rotation (x for D_A, y for D_B, z for D_C).
    angle : array_like, shape S
        Rotation angle [rad], right-handed about ``axis``.

    Returns
    -------
    ndarray, shape S + (4, 4)
        Pure-rotation HTMs (zero translation).

    Raises
    ------
    KeyError
        If ``axis`` is not one of x, y, z.
    """
    angle = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(angle), np.sin(angle)
    out = identity(angle.shape)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    out[..., i, i] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    out[..., j, j] = c
    return out


def rotation_matrix_xyz(ex: ArrayLike, ey: ArrayLike, ez: ArrayLike) -> NDArray:
    """3x3 part of D_A(ex) D_B(ey) D_C(ez), in closed form.

    Parameters
    ----------
    ex, ey, ez : array_like, shape S (broadcast together)
        Rotations [rad] about x, y and z, applied in that order (exact, any size).

    Returns
    -------
    ndarray, shape S + (3, 3)
        Rotation matrices (dimensionless).
    """
    ex, ey, ez = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (ex, ey, ez)))
    ca, sa, cb, sb, cc, sc = np.cos(ex), np.sin(ex), np.cos(ey), np.sin(ey), np.cos(ez), np.sin(ez)
    sa_sb, ca_sb = sa * sb, ca * sb
    # One stacking copy instead of nine strided element writes.
    return np.stack([cb * cc, -cb * sc, sb,
                     sa_sb * cc + ca * sc, -sa_sb * sc + ca * cc, -sa * cb,
                     -ca_sb * cc + sa * sc, ca_sb * sc + sa * cc, ca * cb],
                    axis=-1).reshape(ex.shape + (3, 3))


def rotation_matrix_first_order(ex: ArrayLike, ey: ArrayLike, ez: ArrayLike) -> NDArray:
    """3x3 part of the first-order error matrix of Kidani eq. 2.7.

    Parameters
    ----------
    ex, ey, ez : array_like, shape S (broadcast together)
        Small rotations [rad] about x, y and z.

    Returns
    -------
    ndarray, shape S + (3, 3)
        ``I + skew((ex, ey, ez))``: products of angles dropped, not orthonormal.
    """
    ex, ey, ez = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (ex, ey, ez)))
    one = np.ones_like(ex)
    return np.stack([one, -ez, ey, ez, one, -ex, -ey, ex, one], axis=-1).reshape(ex.shape + (3, 3))


def error_htm_exact(errors: ArrayLike) -> NDArray:
    """D_X(dx) D_Y(dy) D_Z(dz) D_A(ex) D_B(ey) D_C(ez) for
    ``errors[..., :] = (dx, dy, dz, ex, ey, ez)``.

    Parameters
    ----------
    errors : array_like, shape S + (6,)
        Six error motions per joint: translations dx, dy, dz [m] then rotations
        ex, ey, ez [rad].

    Returns
    -------
    ndarray, shape S + (4, 4)
        Exact error HTMs (left side of Kidani eq. 2.7).
    """
    e = np.asarray(errors, dtype=np.float64)
    out = identity(e.shape[:-1])
    out[..., :3, :3] = rotation_matrix_xyz(e[..., 3], e[..., 4], e[..., 5])
    out[..., :3, 3] = e[..., :3]
    return out


def error_htm_first_order(errors: ArrayLike) -> NDArray:
    """The first-order error matrix of Kidani eq. 2.7 / Khan & Chen eq. 7.

    Parameters
    ----------
    errors : array_like, shape S + (6,)
        Six error motions per joint: translations dx, dy, dz [m] then small
        rotations ex, ey, ez [rad].

    Returns
    -------
    ndarray, shape S + (4, 4)
        First-order error HTMs: rotation block ``I + skew((ex, ey, ez))``,
        translation column ``(dx, dy, dz)``.
    """
    e = np.asarray(errors, dtype=np.float64)
    out = identity(e.shape[:-1])
    dx, dy, dz, ex, ey, ez = (e[..., i] for i in range(6))
    out[..., 0, 1], out[..., 0, 2] = -ez, ey
    out[..., 1, 0], out[..., 1, 2] = ez, -ex
    out[..., 2, 0], out[..., 2, 1] = -ey, ex
    out[..., 0, 3], out[..., 1, 3], out[..., 2, 3] = dx, dy, dz
    return out


def rotation_vector(rotation_3x3: ArrayLike) -> NDArray:
    """Rotation vector (axis * angle) of rotation matrices, shape ``S + (3,)``.

    theta = acos((trace - 1) / 2); vector = theta / (2 sin theta) * vee(R - R^T),
    with the series 1 + theta^2 / 6 for small angles (the machine-error case).
    Valid for angles below pi - 1e-6.

    Parameters
    ----------
    rotation_3x3 : array_like, shape S + (3, 3)
        Rotation matrices (a 4x4 HTM's ``[..., :3, :3]`` block).

    Returns
    -------
    ndarray, shape S + (3,)
        Rotation vectors [rad]: unit axis times angle.
    """
    r = np.asarray(rotation_3x3, dtype=np.float64)
    vee = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                    r[..., 1, 0] - r[..., 0, 1]], axis=-1)
    cos_theta = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    theta = np.arccos(cos_theta)
    sin_theta = np.sin(theta)
    small = theta < 1e-4
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(small, 0.5 * (1.0 + theta ** 2 / 6.0), theta / (2.0 * sin_theta))
    return vee * factor[..., None]


def thermal_link_htm(expansion_m: ArrayLike = 0.0, deflection_m: ArrayLike = 0.0,
                     slope_rad: ArrayLike = 0.0, *, length_axis: str = "x",
                     deflection_axis: str = "y") -> NDArray:
    """HTM of a thermally deformed link (Zhu eq. 4.2, section 4.2, Table 4.2).

    The link's end moves by ``expansion_m`` along its length axis and by
    ``deflection_m`` along the deflection axis, and turns by ``slope_rad`` about
    the third axis (right-handed: x, y -> z), as Zhu's epsilon, delta, theta.

    Parameters
    ----------
    expansion_m : array_like, shape S, optional
        Thermal expansion of the link's end along ``length_axis`` [m].
    deflection_m : array_like, shape S, optional
        Bending deflection of the link's end along ``deflection_axis`` [m].
    slope_rad : array_like, shape S, optional
        Bending slope at the link's end [rad], about the third axis.
    length_axis, deflection_axis : {"x", "y", "z"}
        The link's length axis and its deflection axis (must differ).

    Returns
    -------
    ndarray, shape S + (4, 4)
        HTMs of the deformed link, all three inputs broadcast to ``S``.

    Raises
    ------
    ValueError
        If the two axes are not two different of x, y, z.
    """
    axes = "xyz"
    if length_axis not in axes or deflection_axis not in axes or length_axis == deflection_axis:
        raise ValueError(f"length_axis and deflection_axis must be two different of x, y, z, "
                         f"got {length_axis!r}, {deflection_axis!r}")
    normal = next(a for a in axes if a not in (length_axis, deflection_axis))
    expansion, deflection, slope = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (expansion_m, deflection_m, slope_rad)))
    # Right-handedness of (length, deflection, normal) fixes the slope's sign.
    order = axes.index(length_axis), axes.index(deflection_axis), axes.index(normal)
    handed = 1.0 if (order[1] - order[0]) % 3 == 1 else -1.0
    out = rotation(normal, handed * slope)
    out[..., axes.index(length_axis), 3] += expansion
    out[..., axes.index(deflection_axis), 3] += deflection
    return out
