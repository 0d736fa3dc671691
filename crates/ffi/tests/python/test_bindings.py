"""The uniffi Python bindings of jawtrack-ffi driving the same objects the Swift app uses:
Tracker, Recorder, LinkEncoder, Calibrator and the settings checks, on the hinge fixture.

Run by tests/python.rs, which builds the library, generates the bindings into a folder and
passes: BINDINGS_DIR FRAMES_DIR EXPECTED_JSON OUT_DIR. The frames are binary PGM files; the
expected poses come from the Rust tracker."""

import json
import math
import struct
import sys
import unittest
from pathlib import Path

BINDINGS, FRAMES, EXPECTED, OUT = (Path(p) for p in sys.argv[1:5])
sys.path.insert(0, str(BINDINGS))
import jawtrack  # noqa: E402  (generated)

INTRINSICS = jawtrack.Intrinsics(fx=1500.0, fy=1500.0, cx=959.5, cy=539.5, k1=0.0, k2=0.0)
KEY = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff"


def read_pgm(path):
    data = path.read_bytes()
    magic, w, h, maxval, pixels = data.split(maxsplit=4)
    assert magic == b"P5" and maxval == b"255"
    return int(w), int(h), pixels


def frames():
    return [read_pgm(p) for p in sorted(FRAMES.glob("*.pgm"))]


class Bindings(unittest.TestCase):
    def track_all(self, tracker, each=None):
        """Tracks every fixture frame; `each(result)` runs right after each one."""
        results = []
        for i, (w, h, pixels) in enumerate(frames()):
            results.append(tracker.track_luma(pixels, w, h, w, INTRINSICS, i / 30.0, 0.002))
            if each:
                each(results[-1])
        return results

    def test_tracker_gives_the_rust_poses_and_the_overlay(self):
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        results = self.track_all(tracker)
        expected = json.loads(EXPECTED.read_text())
        self.assertEqual(len(results), len(expected))
        for i, (r, want) in enumerate(zip(results, expected)):
            self.assertEqual(r.frame, i)
            self.assertEqual(r.maxilla_from_mandible, want, f"frame {i}")
            self.assertIsNotNone(r.maxilla)
            self.assertEqual(len(r.maxilla.covariance), 36)
            self.assertGreater(len(r.overlay.tags), 3)
            for tag in r.overlay.tags:
                self.assertIn(tag.body, ("maxilla", "mandible"))
                self.assertTrue(all(0.0 <= c <= 1.0 for c in tag.corners), tag.corners)
            self.assertEqual({a.body for a in r.overlay.axes}, {"maxilla", "mandible"})
        self.assertEqual(tracker.last_result(), results[-1])
        self.assertAlmostEqual(results[-1].fps, 30.0, places=6)
        self.assertGreater(tracker.frame_handle(), 0)

    def test_the_intercuspation_step_needs_a_held_bite_then_corrects_and_is_recorded(self):
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        with self.assertRaises(jawtrack.JawTrackError.NotEnoughFrames) as e:
            tracker.calibrate_intercuspation()
        self.assertEqual((e.exception.needed, e.exception.got), (8, 0))
        self.assertIn("needs 8 frames", e.exception.message)
        w, h, pixels = frames()[0]
        # A tenth of a second is not a held bite.
        for i in range(8):
            tracker.track_luma(pixels, w, h, w, INTRINSICS, i / 60.0, None)
        with self.assertRaises(jawtrack.JawTrackError.NotEnoughFrames) as e:
            tracker.calibrate_intercuspation()
        self.assertIn("hold the bite a moment longer", e.exception.message)
        tracker.reset()
        # A jaw opening (the hinge frames one after another) is refused, naming the spread.
        for i, (w, h, px) in enumerate(frames()[:4] * 3):
            tracker.track_luma(px, w, h, w, INTRINSICS, i / 30.0, None)
        with self.assertRaises(jawtrack.JawTrackError.JawMoving) as e:
            tracker.calibrate_intercuspation()
        self.assertGreater(e.exception.spread_mm, 0.3)
        self.assertIn("hold still", e.exception.message)
        tracker.reset()
        # Held still for 0.4 s.
        for i in range(13):
            tracker.track_luma(pixels, w, h, w, INTRINSICS, i / 30.0, None)
        cal = tracker.calibrate_intercuspation()
        self.assertEqual(cal.frames, 13)
        self.assertAlmostEqual(cal.span_s, 0.4, places=9)
        self.assertLess(cal.spread_mm, 0.05, "the same frame thirteen times")
        after = tracker.track_luma(pixels, w, h, w, INTRINSICS, 13 / 30.0, None)
        scan = after.maxilla_scan_from_mandible_scan
        self.assertIsNotNone(scan, "the step sets the registration")
        # The bite just calibrated reads as the scanned intercuspal position (identity).
        self.assertLess(max(abs(scan[3]), abs(scan[7]), abs(scan[11])), 0.05)
        # The rest goes into the recording.
        path = OUT / "bite.jsonl"
        info = jawtrack.RecordingInfo(device="test", intrinsics=INTRINSICS, marker_json=None, settings_json=None,
                                      key_id=None, readout_s=None)
        rec = jawtrack.Recorder.open(str(path), info)
        rec.append(tracker, after.frame)
        rec.append_bite(cal)
        rec.close()
        lines = [json.loads(l) for l in path.read_text().splitlines()]
        bite = lines[2]["bite"]
        self.assertEqual(bite["frames"], 13)
        self.assertEqual(bite["session"], lines[1]["session"])
        self.assertTrue(all(math.isclose(a, b, abs_tol=1e-9) for a, b in zip(bite["maxilla_from_mandible"],
                                                                             cal.maxilla_from_mandible)))

    def test_the_calibrator_collects_views_from_tracked_frames_solves_and_saves(self):
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        cal = jawtrack.Calibrator(tracker.marker_json(), 3)
        start = cal.progress()
        self.assertEqual((start.views, start.min_views, len(start.tags), len(start.needs_views)), (0, 3, 24, 24))
        self.assertEqual(start.min_turn_deg, 5.0)
        self.assertFalse(start.can_solve)
        with self.assertRaises(jawtrack.JawTrackError.Calibration) as e:
            cal.solve()
        self.assertIn("3 views", e.exception.message)
        self.assertIn("no frame to add", cal.add_view(tracker).note)
        progress = []
        for i, (w, h, pixels) in enumerate(frames()):
            tracker.track_luma(pixels, w, h, w, INTRINSICS, i / 30.0, None)
            progress.append(cal.add_view(tracker))
        first, last = progress[0], progress[-1]
        self.assertTrue(first.added)
        self.assertEqual([b.body for b in first.bodies], ["maxilla", "mandible"])
        self.assertEqual([b.last for b in first.bodies], [jawtrack.ViewOutcome.ADDED] * 2)
        self.assertEqual(first.views, 1)
        # Views grow with the lower jaw's opening; the upper jaw holds still: one view.
        counts = [p.views for p in progress]
        self.assertEqual(counts, sorted(counts))
        self.assertGreaterEqual(last.views, 3, counts)
        self.assertEqual(last.bodies[0].views, 1)
        views = {t.id: t.views for t in last.tags}
        self.assertEqual({t.body for t in last.tags if t.id < 12}, {"maxilla"})
        self.assertTrue(all(views[i] <= 1 for i in range(12)), views)
        ready = sorted(i for i, v in views.items() if v >= 3)
        self.assertTrue(ready and all(i >= 12 for i in ready), views)
        # The tags still short of views are named, body by body.
        self.assertEqual(sorted(last.needs_views), sorted(i for i, v in views.items() if v < 3))
        self.assertEqual(last.bodies[1].needs_views, [i for i in range(12, 24) if views[i] < 3])
        self.assertEqual(last.bodies[1].tags_ready, len(ready))
        self.assertTrue(last.can_solve)
        self.assertFalse(last.complete)
        # The same frame again is the same view.
        again = cal.add_view(tracker)
        self.assertFalse(again.added)
        self.assertEqual(again.views, last.views)
        self.assertEqual([b.last for b in again.bodies], [jawtrack.ViewOutcome.SAME_VIEW] * 2)
        self.assertIn("seen from this angle already", again.note)

        result = cal.solve()
        self.assertEqual([b.body for b in result.bodies], ["maxilla", "mandible"])
        self.assertEqual(result.bodies[1].views, last.bodies[1].views)
        self.assertEqual(result.bodies[1].tags_calibrated, len(ready))
        self.assertEqual(len(result.tags), 24)
        rows = {r.id: r for r in result.tags}
        for i in ready:
            r = rows[i]
            self.assertTrue(r.calibrated, r)
            self.assertEqual(r.views, views[i])
            self.assertLess(max(abs(r.shift_x_mm), abs(r.shift_y_mm)), 1.0, r)
            self.assertLess(abs(r.turn_deg), 5.0, r)
            self.assertLessEqual(r.rms_after_px, r.rms_before_px + 1e-9, r)
        for i in set(rows) - set(ready):
            self.assertFalse(rows[i].calibrated)
            self.assertIsNone(rows[i].shift_x_mm)
            self.assertIsNone(rows[i].rms_after_px)
        self.assertTrue(any("too few to calibrate" in f for f in result.findings), result.findings)
        self.assertIsNone(result.focal_warning)

        path = OUT / "calibrated_marker.json"
        cal.save(str(path), False)
        saved = json.loads(path.read_text())
        self.assertEqual(saved, json.loads(result.marker_json))
        status = {t["id"]: t["calibration"] for b in saved["bodies"] for t in b["tags"]}
        for i in ready:
            self.assertEqual(status[i]["status"], "calibrated")
            self.assertEqual(status[i]["views"], views[i])
        self.assertEqual(status[0], {"status": "nominal", "views": 1})
        # The file tracks.
        calibrated = jawtrack.Tracker(jawtrack.default_settings(), path.read_text())
        w, h, pixels = frames()[0]
        self.assertIsNotNone(calibrated.track_luma(pixels, w, h, w, INTRINSICS, 0.0, None).maxilla_from_mandible)
        # Never replaced without being asked.
        before = path.read_text()
        with self.assertRaises(jawtrack.JawTrackError.Io) as e:
            cal.save(str(path), False)
        self.assertIn("already exists", e.exception.message)
        self.assertTrue(e.exception.path.endswith("calibrated_marker.json"))
        self.assertEqual(path.read_text(), before)
        cal.save(str(path), True)
        self.assertEqual(json.loads(path.read_text()), saved)
        self.assertEqual(sorted(p.name for p in OUT.glob("*calibrated_marker*")), ["calibrated_marker.json"])

        # A calibrated file starts a new calibration afresh, from its nominal marker.
        afresh = jawtrack.Calibrator(path.read_text(), 3).progress()
        self.assertEqual((afresh.views, len(afresh.needs_views)), (0, 24))
        cal.reset()
        self.assertEqual(cal.progress().views, 0)
        with self.assertRaises(jawtrack.JawTrackError.InvalidArgument):
            cal.save(str(OUT / "other.json"), False)
        with self.assertRaises(jawtrack.JawTrackError.InvalidMarker) as e:
            jawtrack.Calibrator('{"version": 7}', 3)
        self.assertIn("version", e.exception.message)
        with self.assertRaises(jawtrack.JawTrackError.InvalidSetting) as e:
            jawtrack.Calibrator(None, 0)
        self.assertEqual(e.exception.setting, "min_views")

    def test_misuse_raises_errors_naming_the_problem(self):
        bad = jawtrack.default_settings()
        bad.decimate = 2.5
        with self.assertRaises(jawtrack.JawTrackError.InvalidSetting) as e:
            jawtrack.Tracker(bad, None)
        self.assertEqual(e.exception.setting, "decimate")
        self.assertIn("decimation", e.exception.message)
        with self.assertRaises(jawtrack.JawTrackError.InvalidMarker):
            jawtrack.Tracker(jawtrack.default_settings(), '{"version": 7}')
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        w, h, pixels = frames()[0]
        with self.assertRaises(jawtrack.JawTrackError.InvalidFrame) as e:
            tracker.track_luma(pixels[: len(pixels) // 2], w, h, w, INTRINSICS, 0.0, None)
        self.assertIn("needs", e.exception.message)
        with self.assertRaises(jawtrack.JawTrackError.InvalidFrame):
            tracker.track_luma(pixels, w, h, w - 1, INTRINSICS, 0.0, None)
        broken = jawtrack.Intrinsics(fx=-1.0, fy=1500.0, cx=959.5, cy=539.5, k1=0.0, k2=0.0)
        with self.assertRaises(jawtrack.JawTrackError.InvalidIntrinsics) as e:
            tracker.track_luma(pixels, w, h, w, broken, 0.0, None)
        self.assertEqual(e.exception.message.count("intrinsics"), 1, "said once")
        with self.assertRaises(jawtrack.JawTrackError.InvalidFrame) as e:
            tracker.track_luma(pixels, w, h, w, INTRINSICS, 0.0, -0.002)
        self.assertIn("exposure", e.exception.message)
        choice = jawtrack.readout_for("iPhone16,2", jawtrack.Camera.BACK_WIDE, None)
        self.assertTrue(choice.known)
        self.assertAlmostEqual(choice.readout_s, 0.0051)
        with self.assertRaises(jawtrack.JawTrackError.InvalidSetting):
            tracker.update_settings(bad)
        settings = jawtrack.default_app_settings()
        jawtrack.validate_app_settings(settings, False)
        with self.assertRaises(jawtrack.JawTrackError.InvalidSetting) as e:
            jawtrack.validate_app_settings(settings, True)
        self.assertEqual(e.exception.setting, "receiver_host")
        self.assertIn("receiver host", e.exception.message)
        self.assertEqual(len(jawtrack.pairing_key_id(" " + KEY + "\n")), 16)
        with self.assertRaises(jawtrack.JawTrackError.InvalidKey):
            jawtrack.pairing_key_id("not a key")

    def test_intrinsics_scale_to_the_delivered_frame(self):
        # AVFoundation's matrix, column-major, for a 4032×3024 reference; frame 1920×1440.
        m = [2800.0, 0, 0, 0, 2800.0, 0, 2016.0, 1512.0, 1.0]
        k = jawtrack.intrinsics_from_camera_matrix(m, 4032, 3024, 1920, 1440)
        s = 1920 / 4032
        self.assertAlmostEqual(k.fx, 2800.0 * s, places=3)
        self.assertAlmostEqual(k.cx, 2016.0 * s - 0.5, places=3)
        with self.assertRaises(jawtrack.JawTrackError.InvalidIntrinsics):
            jawtrack.intrinsics_from_camera_matrix(m[:8], 4032, 3024, 1920, 1440)

    def test_the_recorder_writes_the_track_schema_line_by_line(self):
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        path = OUT / "session.jsonl"
        info = jawtrack.RecordingInfo(device="test", intrinsics=INTRINSICS, marker_json=tracker.marker_json(),
                                      settings_json='{"fps": 30}', key_id=None, readout_s=0.0051)
        rec = jawtrack.Recorder.open(str(path), info)

        def append(r):
            rec.append(tracker, r.frame)
            # Flushed per frame: the file already holds every line appended.
            self.assertEqual(len(path.read_text().splitlines()), 1 + rec.frames_written())

        results = self.track_all(tracker, append)
        self.assertEqual(rec.frames_written(), len(results))
        # Only the frame just tracked: an older one is refused, not recorded as if it were new.
        with self.assertRaises(jawtrack.JawTrackError.InvalidArgument) as e:
            rec.append(tracker, results[0].frame)
        self.assertIn("not the last frame tracked", e.exception.message)
        rec.close()
        with self.assertRaises(jawtrack.JawTrackError.InvalidArgument):
            rec.append(tracker, results[-1].frame)
        lines = [json.loads(l) for l in path.read_text().splitlines()]
        self.assertEqual(lines[0]["recording"]["source"], "JawTrack iOS")
        self.assertEqual(lines[0]["recording"]["settings"], {"fps": 30})
        self.assertEqual(lines[0]["recording"]["readout_s"], 0.0051)
        for line, r in zip(lines[1:], results):
            self.assertEqual(line["frame"], r.frame)
            self.assertEqual(line["exposure_s"], 0.002)
            got = line["maxilla_from_mandible"]
            self.assertTrue(all(math.isclose(a, b, abs_tol=1e-9) for a, b in zip(got, r.maxilla_from_mandible)))
            self.assertEqual(len(line["maxilla"]["cov"]), 36)
        # The tracker's own line, as `jawtrack track` writes it: the region searched included.
        self.assertTrue(any(line.get("searched") for line in lines[2:]), "no frame recorded its search region")
        with self.assertRaises(jawtrack.JawTrackError.Io) as e:
            jawtrack.Recorder.open(str(OUT / "no-such-folder" / "x.jsonl"), info)
        self.assertTrue(e.exception.path.endswith("x.jsonl"), e.exception.path)
        # A recording is never replaced.
        before = path.read_text()
        with self.assertRaises(jawtrack.JawTrackError.Io) as e:
            jawtrack.Recorder.open(str(path), info)
        self.assertIn("already exists", e.exception.message)
        self.assertEqual(path.read_text(), before)

    def test_the_link_encoder_seals_datagrams_libsodium_can_open(self):
        tracker = jawtrack.Tracker(jawtrack.default_settings(), None)
        r = self.track_all(tracker)[-1]
        enc = jawtrack.LinkEncoder(KEY, False)
        first, second = enc.encode(tracker, r.frame), enc.encode(tracker, r.frame)
        self.assertEqual(len(first), 264)
        magic, version, kind, security, _, session, seq, _ = struct.unpack("<4sBBBBQQQ", first[:32])
        self.assertEqual((magic, version, kind, security, session, seq), (b"JAWT", 1, 1, 1, enc.session_id(), 0))
        self.assertEqual(struct.unpack("<Q", second[16:24])[0], 1)
        self.assertEqual(enc.key_id(), jawtrack.pairing_key_id(KEY))
        with self.assertRaises(jawtrack.JawTrackError.Link):
            enc.read_ack(b"garbage")
        with self.assertRaises(jawtrack.JawTrackError.Link):
            enc.read_ack(first)  # a pose, not an acknowledgement
        with self.assertRaises(jawtrack.JawTrackError.InvalidArgument):
            jawtrack.LinkEncoder(None, False)
        with self.assertRaises(jawtrack.JawTrackError.InvalidKey):
            jawtrack.LinkEncoder("not a key", False)
        try:
            from nacl.bindings import crypto_aead_xchacha20poly1305_ietf_decrypt
        except ImportError:
            print("SKIPPED: opening the datagram with libsodium: PyNaCl is not installed")
            return
        nonce = bytes([1]) + bytes(7) + first[8:24]
        body = crypto_aead_xchacha20poly1305_ietf_decrypt(first[32:], first[:32], nonce, bytes.fromhex(KEY))
        t, frame = struct.unpack("<dQ", body[:16])
        self.assertEqual((t, frame), (r.t, r.frame))
        tx, ty, tz = struct.unpack("<3d", body[136 + 32:136 + 56])
        m = r.maxilla_from_mandible
        self.assertTrue(all(math.isclose(a, b, abs_tol=1e-9) for a, b in [(tx, m[3]), (ty, m[7]), (tz, m[11])]))


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
