"""The drop model's terms (rigopt/metrics/drop_model.py): closed forms of each term on moved copies of one camera,
invariances, the fit recovering known weights, and the conformal half-widths' ranks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigopt.geometry import rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation
from rigopt.metrics import drop_model as dm
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig


def one_camera(z=1.5, yaw=0.0, pitch=0.0, roll=0.0, fov=65.0, xy=(2.0, 0.0)) -> Rig:
    rotation = rotation_from_yaw_pitch_roll(np.radians(yaw), np.radians(pitch), np.radians(roll))
    return Rig("one", "vehicle.audi.etron", (Camera.pinhole("CAM", np.array([*xy, z]), rotation, fov),))


def terms(a: Rig, b: Rig) -> dict[str, float]:
    t = dm.PairTerms.of(a, b)
    return dict(zip(dm.FEATURES, dm.matched_features(t.pairs, t.rig, np.ones(len(dm.PAIR_FEATURES)))))


def test_a_rig_against_itself_has_no_term_and_loses_nothing():
    r1 = load_rig("R1")
    t = dm.PairTerms.of(r1, r1)
    assert np.allclose(dm.matched_features(t.pairs, t.rig, np.ones(len(dm.PAIR_FEATURES))), 0, atol=1e-12)
    assert dm.predict(np.ones(len(dm.FEATURES)), [t])[0] == pytest.approx(0, abs=1e-12)


@pytest.mark.parametrize("moved, expected", [
    ({"z": 2.0}, {"raise": 0.5, "lower": 0.0}),
    ({"z": 1.2}, {"raise": 0.0, "lower": 0.3}),
    ({"pitch": -10.0}, {"tilt_down": np.radians(10), "tilt_up": 0.0}),
    ({"pitch": 4.0}, {"tilt_up": np.radians(4), "tilt_down": 0.0}),
    ({"roll": -6.0}, {"roll": np.radians(6)}),
    ({"yaw": 200.0}, {"yaw": np.radians(160)}),
    ({"xy": (2.0, 1.0)}, {"plan": 1.0}),
    ({"fov": 90.0}, {"zoom": abs(np.log(np.tan(np.radians(45)) / np.tan(np.radians(32.5))))}),
])
def test_each_term_of_one_moved_camera_has_its_closed_form(moved, expected):
    found = terms(one_camera(), one_camera(**moved))
    for name, value in expected.items():
        assert found[name] == pytest.approx(value, abs=1e-9), name
    untouched = set(dm.PAIR_FEATURES) - set(expected) - {"depth_prior"}
    assert all(found[name] == pytest.approx(0, abs=1e-9) for name in untouched)


def test_a_camera_pitched_down_or_lowered_sees_the_ground_nearer_so_the_depth_prior_moves():
    base = one_camera()
    assert terms(base, one_camera(pitch=-10.0))["depth_prior"] > 0.05
    # a level camera: the lower half of the grid meets the ground at depths in ratio 1.5 (within range), the
    # upper half never (the far end for both)
    assert 0.1 < terms(base, one_camera(z=1.0))["depth_prior"] < 0.5 * np.log(1.5) + 1e-9
    assert terms(base, one_camera(xy=(0.0, 1.0), yaw=90.0))["depth_prior"] == pytest.approx(0, abs=1e-12)


def test_terms_do_not_depend_on_the_order_of_the_cameras():
    r1, r6 = load_rig("R1"), load_rig("R6")
    shuffled = dataclasses.replace(r6, cameras=tuple(reversed(r6.cameras)))
    np.testing.assert_allclose(list(terms(r1, r6).values()), list(terms(r1, shuffled).values()), atol=1e-12)


def test_the_count_and_uncovered_terms_of_a_front_camera_alone():
    r1 = load_rig("R1")
    front = dataclasses.replace(r1, cameras=r1.cameras[:1])
    found = terms(r1, front)
    assert found["count"] == pytest.approx(7 / 8)
    yaw = yaw_pitch_roll_from_rotation(r1.cameras[0].rotation)[0]
    own = dm.azimuth_cover(dm.CameraGeometry.of(front))
    seen = dm.azimuth_cover(dm.CameraGeometry.of(r1))
    assert found["uncovered"] == pytest.approx((seen & ~own).sum() / seen.sum())
    assert abs(yaw) < 0.01 and 60 <= own.sum() <= 70  # a 65 degree lens covers about 65 one-degree sectors


def test_the_fit_recovers_weights_that_made_the_drops():
    """Drops made by the model itself from known weights on 40 moved copies of R1 are fitted back."""
    r1 = load_rig("R1")
    rng = np.random.default_rng(0)
    candidates = []
    for _ in range(40):
        dz, pitch, yaw = rng.uniform(-0.3, 0.8), rng.uniform(-12, 4), rng.uniform(-20, 20)
        cameras = []
        for camera in r1.cameras:
            y, p, r = yaw_pitch_roll_from_rotation(camera.rotation)
            cameras.append(dataclasses.replace(camera, position=camera.position + [0, 0, dz],
                                               rotation=rotation_from_yaw_pitch_roll(y + np.radians(yaw),
                                                                                     p + np.radians(pitch), r)))
        candidates.append(dataclasses.replace(r1, cameras=tuple(cameras)))
    truth = np.zeros(len(dm.FEATURES))
    truth[[dm.FEATURES.index("raise"), dm.FEATURES.index("tilt_down"), dm.FEATURES.index("yaw")]] = [1.2, 4.0, 0.3]
    t = [dm.PairTerms.of(r1, c) for c in candidates]
    drops = dm.predict(truth, t)
    weights = dm.fit_weights(t, drops)
    assert (weights >= 0).all()
    np.testing.assert_allclose(dm.predict(weights, t), drops, atol=1e-4)


def test_conformal_halfwidths_take_the_rank_of_the_level():
    predicted = np.array([0.1] * 9 + [0.3] * 8)
    measured = predicted + np.r_[np.arange(1, 10) / 10, np.arange(1, 9) / 100]
    widths = dm.interval_halfwidths(predicted, measured, 0.9)
    assert widths[0] == pytest.approx(0.9)  # ceil(10 x 0.9) = 9th of 9
    assert widths[1] == np.inf  # the 9th of 8 does not exist
    assert widths[2] == np.inf  # no prediction in the bin
    np.testing.assert_array_equal(dm.interval_bin([0.0, 0.15, 0.39, 0.4, 0.9]), [0, 1, 1, 2, 2])


def test_a_term_no_fitting_rig_has_gets_no_weight():
    """Roll and the principal point never move in these rigs (rounding noise at most): their weights are 0, so a
    later rig that has them is not predicted from a weight the fit never saw evidence for."""
    r1 = load_rig("R1")
    candidates = [dataclasses.replace(r1, cameras=tuple(dataclasses.replace(c, position=c.position + [0, 0, dz])
                                                        for c in r1.cameras)) for dz in (0.1, 0.3, 0.5, 0.9)]
    t = [dm.PairTerms.of(r1, c) for c in candidates]
    weights = dm.fit_weights(t, np.array([0.05, 0.2, 0.35, 0.6]))
    for name in ("roll", "centre", "tilt_down", "tilt_up", "yaw", "zoom", "count", "uncovered", "lower"):
        assert weights[dm.FEATURES.index(name)] == 0, name


def a_model(weights=None, default=True, ranges=(0.0, 1.0)) -> dm.DropModel:
    """A model of every term at 0.2 but ``body`` (0: it predicts without body shares), or of ``weights``."""
    reference = load_rig("R1")
    n = len(dm.FEATURES)
    if weights is None:
        weights = np.where(np.equal(dm.FEATURES, "body"), 0.0, 0.2)
    return dm.DropModel("test", "lss-R1", "R1", dm.camera_table(reference), np.asarray(weights, float),
                        np.array([0.05, 0.1, 0.2]), np.tile(ranges, (n, 1)), default, "a test model")


def test_a_model_predicts_what_its_weights_and_matching_say():
    model, r1 = a_model(), load_rig("R1")
    raised = dataclasses.replace(r1, cameras=tuple(dataclasses.replace(c, position=c.position + [0, 0, 0.5])
                                                   for c in r1.cameras))
    drops, halfwidths, beyond = model.predict(r1, [r1, raised])
    t = dm.PairTerms.of(r1, raised)
    assert drops[0] == pytest.approx(0, abs=1e-12)
    assert drops[1] == pytest.approx(dm.predict(model.weights, [t])[0], abs=1e-12)
    assert drops[1] == pytest.approx(1 - np.exp(-0.2 * 0.5 - 0.2 * terms(r1, raised)["depth_prior"]), abs=1e-9)
    assert halfwidths.tolist() == [0.05, model.halfwidths[dm.interval_bin(drops[1:])[0]]]
    assert beyond == [{}, {}]


def test_a_term_beyond_the_fitting_rigs_is_flagged_only_where_it_has_weight():
    r1 = load_rig("R1")
    raised = dataclasses.replace(r1, cameras=tuple(dataclasses.replace(c, position=c.position + [0, 0, 2.0])
                                                   for c in r1.cameras))
    flagged = a_model().predict(r1, [raised])[2][0]
    assert flagged["raise"] == pytest.approx((2.0, 0.0, 1.0)) and "lower" not in flagged
    weights = a_model().weights.copy()
    weights[dm.FEATURES.index("raise")] = 0.0
    assert "raise" not in a_model(weights).predict(r1, [raised])[2][0]


def test_a_model_applies_to_its_reference_only():
    model, r1 = a_model(), load_rig("R1")
    assert model.applies_to(r1)
    assert not model.applies_to(load_rig("R2"))
    nudged = dataclasses.replace(r1, cameras=(dataclasses.replace(r1.cameras[0], position=r1.cameras[0].position
                                                                  + [0.01, 0, 0]), *r1.cameras[1:]))
    assert not model.applies_to(nudged)
    assert not model.applies_to(dataclasses.replace(r1, cameras=r1.cameras[:-1]))


def test_a_model_survives_its_json_form():
    model = a_model()
    again = dm.DropModel.from_dict(model.to_dict())
    assert again.to_dict() == model.to_dict()
    data = model.to_dict()
    data["features"] = data["features"][::-1]
    with pytest.raises(ValueError, match="terms"):
        dm.DropModel.from_dict(data)


def test_the_predictor_option_picks_the_default_model_for_its_reference_and_rigcd_elsewhere(monkeypatch):
    from rigopt.errors import RigoptError, UnknownNameError

    monkeypatch.setattr(dm, "shipped_drop_models", lambda: ["test"])
    monkeypatch.setattr(dm, "load_drop_model", lambda name: a_model(default=True))
    r1, r2 = load_rig("R1"), load_rig("R2")
    assert dm.choose_model("auto", r1).name == "test"
    assert dm.choose_model("auto", r1, weights_given=True) is None  # named RigCD weights: RigCD
    assert dm.choose_model("auto", r2) is None
    assert dm.choose_model("rigcd", r1) is None
    assert dm.choose_model("TEST", r1).name == "test"
    with pytest.raises(RigoptError, match="predicts transfers from R1"):
        dm.choose_model("test", r2)
    with pytest.raises(UnknownNameError, match="auto, rigcd, test"):
        dm.choose_model("nope", r1)
    monkeypatch.setattr(dm, "load_drop_model", lambda name: a_model(default=False))
    assert dm.choose_model("auto", r1) is None  # a model its study did not find better prints only when named


def test_transfer_predictions_carry_the_model_and_keep_rigcd():
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer

    r1, r2 = load_rig("R1"), load_rig("R2")
    calibration = load_weights("joint")
    plain = predict_transfer(r1, [r2], calibration)[0]
    model = a_model()
    modelled = predict_transfer(r1, [r2], calibration, model)[0]
    drop, halfwidth = model.predict(r1, [r2])[0][0], model.predict(r1, [r2])[1][0]
    assert plain.predictor == "RigCD (joint)" and modelled.predictor == "test drop model"
    assert modelled.predicted_drop == pytest.approx(drop)
    assert modelled.interval == pytest.approx((drop - halfwidth, min(drop + halfwidth, 1)))
    assert (modelled.rigcd, modelled.t, modelled.count) == (plain.rigcd, plain.t, plain.count)
    assert modelled.linear_drop is None and modelled.to_dict()["predictor"] == "test drop model"


def shares(values: dict[str, list[float]]):
    """A body_share function that gives each rig (by name) its listed shares."""
    return lambda rig, grid: np.asarray(values[rig.name], dtype=float)


def test_the_body_term_is_the_candidates_extra_share_of_ego_body():
    a, b = one_camera(), dataclasses.replace(one_camera(), name="two")
    t = dm.PairTerms.of(a, b, shares({"one": [0.1], "two": [0.4]}))
    assert t.pairs[0, 0, dm.PAIR_FEATURES.index("body")] == pytest.approx(0.3)
    t = dm.PairTerms.of(a, b, shares({"one": [0.4], "two": [0.1]}))  # seeing less body than the reference: 0
    assert t.pairs[0, 0, dm.PAIR_FEATURES.index("body")] == 0
    assert dm.PairTerms.of(a, b).pairs[0, 0, dm.PAIR_FEATURES.index("body")] == 0  # no shares given: none


def test_a_model_that_weighs_the_body_needs_the_shares_and_adds_their_weight():
    r1 = load_rig("R1")
    blinded = dataclasses.replace(r1, name="blinded")
    weights = a_model().weights.copy()
    weights[dm.FEATURES.index("body")] = 2.0
    model = a_model(weights)
    assert model.needs_body and not a_model().needs_body
    with pytest.raises(ValueError, match="body_share"):
        model.predict(r1, [blinded])
    half = shares({"R1": [0.0] * 8, "blinded": [0.5] * 8})
    drop = model.predict(r1, [blinded], half)[0][0]
    assert drop == pytest.approx(1 - np.exp(-2.0 * 0.5), abs=1e-12)


def test_a_model_file_of_fewer_terms_weighs_the_others_zero_and_keeps_its_form():
    data = a_model().to_dict()
    keep = [k for k, name in enumerate(data["features"]) if name != "body"]
    data.update(features=[data["features"][k] for k in keep], weights=[data["weights"][k] for k in keep],
                ranges=[data["ranges"][k] for k in keep])
    model = dm.DropModel.from_dict(data)
    assert model.features == tuple(data["features"]) and model.weights[dm.FEATURES.index("body")] == 0
    assert model.to_dict() == data
    data["weights"] = data["weights"][:-1]
    with pytest.raises(ValueError, match="one per term"):
        dm.DropModel.from_dict(data)


def test_a_camera_facing_into_its_vehicle_sees_its_body_and_one_on_an_unknown_vehicle_none():
    from rigopt.geometry import rot_z
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.vehicle.placement import in_vehicle_frame

    r1 = in_vehicle_frame(load_rig("R1"))[0]
    assert np.all(rig_body_share(r1, dm.BODY_GRID) < 0.05)
    inward = dataclasses.replace(r1, cameras=tuple(dataclasses.replace(c, rotation=rot_z(np.pi) @ c.rotation)
                                                   for c in r1.cameras))
    assert np.all(rig_body_share(inward, dm.BODY_GRID) > 0.5)
    unknown = dataclasses.replace(inward, vehicle="a vehicle rigopt does not know")
    assert np.all(rig_body_share(unknown, dm.BODY_GRID) == 0)
