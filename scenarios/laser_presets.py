"""Datasheet models of the 2D lasers of the seeds, for the scenario key ``sensors.lasers[i].preset``.

Range error: each band gives, up to its range, the systematic error (an offset of the laser's readings, within +-
the bound, drawn once per laser and the same on every beam) and the statistical error (1 sigma, drawn anew for every
return), as the manufacturers state them.

* ``sick_lms500``: the SPENCER robot's two back-to-back lasers (seed 000: SICK LMS 500 at 70 cm, 190 degrees at
  0.25 or 0.5 degrees, 25 or 50 Hz, detections up to 20 m). Errors from SICK's knowledge base "Measurement errors
  LMSxxx" for the LMS5xx HR: systematic +-25 mm (1-10 m), +-35 mm (10-20 m); statistical 7 mm (1-10 m), 9 mm
  (10-20 m).
* ``hokuyo_utm30lx``: Hokuyo UTM-30LX specification: 270 degrees at 0.25 degrees, 25 ms per scan (40 Hz),
  0.1-30 m; accuracy +-30 mm (0.1-10 m), +-50 mm (10-30 m); repeated accuracy sigma < 10 mm (0.1-10 m),
  < 30 mm (10-30 m).
* ``sick_s300``: the DROW dataset's laser (Beyer et al. 2016: a SICK S300 at 37 cm, "225 degrees in 450 points");
  its beam grid as DROW's and DR-SPAAM's loaders build it: 450 beams 0.5 degrees apart, so 224.5 degrees from
  first to last (DROW ``v2/utils/__init__.py``: ``laserFoV = (450-1)*laserIncrement``; DR-SPAAM
  ``dr_spaam/dr_spaam/datahandle/drow_handle.py``: ``get_laser_phi``), and a scan exports to DROW beam for beam;
  40 ms per scan (25 Hz) per the S300 datasheet. SICK publishes no range error for the S300's measurement output:
  the errors here are the LMS1xx's typical figures from the same knowledge base (systematic +-30 mm, statistical
  12 mm), an assumption.
"""

from sensors.laser import SICK_LMS500_NOISE

LASER_PRESETS = {
    "sick_lms500": {
        "height": 0.70, "fov_deg": 190.0, "resolution_deg": 0.5, "range_min": 0.0, "range_max": 20.0, "rate": 25.0,
        "noise": SICK_LMS500_NOISE,
    },
    "hokuyo_utm30lx": {
        "fov_deg": 270.0, "resolution_deg": 0.25, "range_min": 0.1, "range_max": 30.0, "rate": 40.0,
        "noise": [{"up_to": 10.0, "systematic": 0.030, "statistical": 0.010},
                  {"up_to": 30.0, "systematic": 0.050, "statistical": 0.030}],
    },
    "sick_s300": {
        "height": 0.37, "fov_deg": 224.5, "resolution_deg": 0.5, "range_min": 0.0, "range_max": 30.0, "rate": 25.0,
        "noise": [{"up_to": 30.0, "systematic": 0.030, "statistical": 0.012}],
    },
}
