"""Closed cubic B-spline boundaries of rasterised masks (real pixels via OpenCV drawing)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.body.spline import (
    combined_shape_vector,
    design_matrix,
    evaluate_closed_bspline,
    fit_closed_bspline,
    oriented_boundary,
    silhouette_spline,
    spline_distance,
)

H, W = 240, 240


def circle(cx: int = 120, cy: int = 110, r: int = 50) -> np.ndarray:
    m = np.zeros((H, W), np.uint8)
    cv2.circle(m, (cx, cy), r, 1, thickness=-1)
    return m.astype(bool)


def ellipse(cx: int = 120, cy: int = 120, ax: int = 30, ay: int = 80, angle: float = 0.0) -> np.ndarray:
    m = np.zeros((H, W), np.uint8)
    cv2.ellipse(m, (cx, cy), (ax, ay), angle, 0, 360, 1, thickness=-1)
    return m.astype(bool)


def rectangle(x0: int = 90, y0: int = 50, x1: int = 150, y1: int = 190) -> np.ndarray:
    m = np.zeros((H, W), bool)
    m[y0 : y1 + 1, x0 : x1 + 1] = True
    return m


def person() -> np.ndarray:
    """Head, torso, legs and one raised arm: a non-convex outline."""
    m = np.zeros((H, W), np.uint8)
    cv2.circle(m, (120, 40), 16, 1, -1)
    cv2.rectangle(m, (100, 56), (140, 140), 1, -1)
    cv2.rectangle(m, (102, 140), (116, 225), 1, -1)
    cv2.rectangle(m, (124, 140), (138, 225), 1, -1)
    cv2.line(m, (140, 62), (175, 20), 1, thickness=9)
    return m.astype(bool)


SHAPES = {
    "circle": circle,
    "ellipse": ellipse,
    "wide_ellipse": lambda: ellipse(ax=90, ay=40),
    "tilted_ellipse": lambda: ellipse(angle=20.0),
    "rectangle": rectangle,
    "person": person,
}


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_spline_fits_boundary_within_one_pixel(name):
    mask = SHAPES[name]()
    ctrl, ref = silhouette_spline(mask, n=32)
    contour, ref2 = oriented_boundary(mask)
    assert ctrl.shape == (32, 2)
    np.testing.assert_array_equal(ref, ref2)
    assert spline_distance(contour, ctrl) < 1.0


@pytest.mark.parametrize("name", ["circle", "ellipse", "wide_ellipse", "rectangle"])
def test_first_control_point_is_top_centre_and_order_goes_left_first(name):
    mask = SHAPES[name]()
    ctrl, ref = silhouette_spline(mask)
    rows, cols = np.nonzero(mask)
    top = rows.min()
    centre_x = cols[rows == top].mean()
    assert abs(ref[1] - top) < 0.5 and abs(ref[0] - centre_x) <= 1.0
    # The curve starts at the reference point; control point 0 is the one that shapes it there
    # (outside a convex curve by up to a few pixels where the outline bends sharply).
    start = evaluate_closed_bspline(ctrl)[0]
    assert np.hypot(*(start - ref)) < 1.0
    assert abs(ctrl[0, 0] - centre_x) < 2.0 and abs(ctrl[0, 1] - top) < 3.0
    if name != "rectangle":  # a rectangle's corner control points overshoot above its top
        assert ctrl[0, 1] <= ctrl[:, 1].min() + 1.0
    # Counter-clockwise on screen: from the top towards image-left, bottom half-way round.
    assert ctrl[1, 0] < ctrl[0, 0] - 3.0
    assert ctrl[16, 1] > rows.mean() + 0.3 * (rows.max() - rows.mean())


def test_reference_point_is_top_of_head_not_raised_hand():
    mask = person()
    ctrl, ref = silhouette_spline(mask)
    # Head circle centred (120, 40), radius 16: top of head at about (120, 24). The raised hand
    # reaches higher (y ~ 16) but lies off the body axis.
    assert abs(ref[0] - 120) <= 3 and abs(ref[1] - 24) <= 1
    assert np.hypot(*(evaluate_closed_bspline(ctrl)[0] - ref)) < 1.5
    assert abs(ctrl[0, 0] - 120) <= 3


def test_tilted_ellipse_reference_on_principal_axis_then_locally_highest():
    mask = ellipse(angle=20.0)
    contour, ref = oriented_boundary(mask)
    # Locally highest: no boundary point within 10 samples either side is higher.
    window = np.concatenate([contour[:10], contour[-10:]])
    assert ref[1] <= window[:, 1].min()
    # And it is at the upper end of the tilted major axis (right of centre, near the top).
    assert ref[0] > 120 and ref[1] < 60


def test_control_points_are_evenly_spaced_along_the_curve():
    ctrl, _ = silhouette_spline(ellipse(), n=32)
    knots = evaluate_closed_bspline(ctrl, samples_per_span=1)  # curve at u = 0, 1, ..., n-1
    gaps = np.hypot(*np.diff(np.vstack([knots, knots[:1]]), axis=0).T)
    assert gaps.std() / gaps.mean() < 0.1


def test_fit_recovers_a_known_spline():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    true = np.stack([100 + 40 * np.cos(t), 100 - 60 * np.sin(t)], axis=1) + rng.normal(0, 4, (12, 2))
    curve = evaluate_closed_bspline(true, samples_per_span=40)
    ctrl = fit_closed_bspline(curve, n=12)
    # Arc-length and uniform parameterisations differ a little: small but non-zero error.
    assert spline_distance(curve, ctrl) < 0.5
    # Fitting a dense sample of the curve with the same parameterisation is exact.
    exact = fit_closed_bspline(evaluate_closed_bspline(true, 8), n=12, resample=False)
    np.testing.assert_allclose(exact, true, atol=1e-8)


def test_design_matrix_is_cached_partition_of_unity_and_read_only():
    a = design_matrix(256, 32)
    assert a is design_matrix(256, 32)
    np.testing.assert_allclose(a.sum(axis=1), 1.0)
    assert (np.count_nonzero(a, axis=1) <= 4).all()
    with pytest.raises(ValueError):
        a[0, 0] = 1.0


def test_errors_name_the_problem():
    with pytest.raises(ValueError, match="empty"):
        silhouette_spline(np.zeros((20, 20), bool))
    with pytest.raises(ValueError, match="n >= 4"):
        fit_closed_bspline(np.random.default_rng(0).normal(size=(50, 2)), n=3)
    with pytest.raises(ValueError, match=r"\(M, 2\)"):
        fit_closed_bspline(np.zeros((10, 3)))


def test_combined_shape_vector_layout_and_invariance():
    ca, ref_a = silhouette_spline(ellipse(cx=70, ay=70))
    cb, ref_b = silhouette_spline(ellipse(cx=170, ax=25, ay=60))
    pa, pb = np.array([70.0, 120.0]), np.array([170.0, 120.0])
    ha, hb = 141.0, 121.0
    v = combined_shape_vector(ca, ha, pa, cb, hb, pb)
    n = len(ca)
    assert v.shape == (4 * n + 3,)
    np.testing.assert_allclose(v[: 2 * n].reshape(n, 2), (ca - pa) / ha)
    np.testing.assert_allclose(v[2 * n : 4 * n].reshape(n, 2), (cb - pb) / hb)
    np.testing.assert_allclose(v[4 * n : 4 * n + 2], (pb - pa) / ((ha + hb) / 2))
    assert v[4 * n + 2] == pytest.approx(np.log(hb / ha))
    # The same scene shifted and zoomed gives the same vector.
    s, shift = 1.7, np.array([-30.0, 12.0])
    v2 = combined_shape_vector(ca * s + shift, ha * s, pa * s + shift, cb * s + shift, hb * s, pb * s + shift)
    np.testing.assert_allclose(v2, v, atol=1e-12)
    # Swapping who is who changes the sign of separation and relative scale.
    vs = combined_shape_vector(cb, hb, pb, ca, ha, pa)
    np.testing.assert_allclose(vs[4 * n :], -v[4 * n :])
    with pytest.raises(ValueError, match="height"):
        combined_shape_vector(ca, 0.0, pa, cb, hb, pb)


def test_up_axis_closed_form_matches_eigh() -> None:
    """The closed-form principal axis equals np.linalg.eigh's on rotated ellipses, thin lines and
    blobs: the same direction to 1e-9 and the same fallback to the vertical.
    """
    from counterpart.body.spline import _up_axis

    rng = np.random.default_rng(0)
    masks = [
        ellipse(ax=int(rng.integers(3, 60)), ay=int(rng.integers(3, 90)), angle=float(rng.uniform(0, 180)))
        for _ in range(150)
    ]
    masks += [rectangle(120, 20, 120, 200), rectangle(20, 120, 200, 120), circle(), person()]
    n_vertical = 0
    for m in masks:
        m8 = m.view(np.uint8)
        c, up = _up_axis(m8)
        mo = cv2.moments(m8, binaryImage=True)
        cov = np.array([[mo["mu20"], mo["mu11"]], [mo["mu11"], mo["mu02"]]]) / mo["m00"]
        evals, evecs = np.linalg.eigh(cov)
        d = evecs[:, 1]
        if evals[1] < 1.1 * evals[0] or abs(d[1]) < np.sqrt(0.5):
            ref = np.array([0.0, -1.0])
            n_vertical += 1
        else:
            ref = d if d[1] < 0 else -d
        np.testing.assert_allclose(up, ref, atol=1e-9)
        np.testing.assert_allclose(c, [mo["m10"] / mo["m00"], mo["m01"] / mo["m00"]])
    assert 0 < n_vertical < len(masks)  # both branches were exercised


@pytest.mark.parametrize("dtype", [bool, np.uint8, np.int32])
def test_oriented_boundary_reads_any_nonzero_mask_alike(dtype: type) -> None:
    """A bool, a 0/255 uint8 and an int mask of one shape give the same boundary, and the uint8
    mask is left as it was.
    """
    m = person()
    ref_c, ref_p = oriented_boundary(m)
    m2 = m.astype(dtype) * (255 if dtype is np.uint8 else 7) if dtype is not bool else m.copy()
    before = m2.copy()
    c, p = oriented_boundary(m2)
    np.testing.assert_array_equal(c, ref_c)
    np.testing.assert_array_equal(p, ref_p)
    np.testing.assert_array_equal(m2, before)
