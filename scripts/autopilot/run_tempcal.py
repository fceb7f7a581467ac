"""Run ArduPilot's tempcal_IMU.py (as published in ardupilot-methodic-configurator on PyPI,
file ardupilot_methodic_configurator/tempcal_imu.py, unmodified) on a DataFlash log, with the
log's PARM records handed to it before its IMU records.

Why: the script reads PARM and IMU records in file order and applies the log's existing
INS_TCALn calibration to each IMU record with the parameters read so far. In a real log the
parameter burst at the start can interleave with the first IMU records (here INS_TCAL3's
coefficients come after IMU[2]'s first record), and the published script then stops with
`KeyError: 2`. The firmware loaded those parameters from storage at boot, before logging, so
the values in force for every record are the logged ones: this wrapper gives the script
exactly that order and changes nothing else.

Usage: python run_tempcal.py TEMPCAL_PY LOG OUTFILE
"""
import importlib.util
import sys

from pymavlink import mavutil

tool_path, log, outfile = sys.argv[1:4]
spec = importlib.util.spec_from_file_location("tempcal_imu", tool_path)
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)

real_connect = mavutil.mavlink_connection


class ParamsFirst:
    def __init__(self, path, **kw):
        self._conn = real_connect(path, **kw)
        parms = real_connect(path)
        self._parms = []
        while True:
            m = parms.recv_match(type=["PARM"])
            if m is None:
                break
            self._parms.append(m)

    def __getattr__(self, name):
        return getattr(self._conn, name)

    def recv_match(self, type=None):
        want = [t for t in type if t != "PARM"]
        if self._parms and "PARM" in type:
            return self._parms.pop(0)
        return self._conn.recv_match(type=want)


tool.mavutil.mavlink_connection = ParamsFirst
tool.IMUfit(log, outfile, True, False, False, False, None, None)
