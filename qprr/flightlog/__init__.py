"""Flight logs: PX4 ULog read (pyulog, the ``flightlog`` extra), shown, replayed through PX4's mix and a qprr
platform, and used to identify the robot that flew.

ulog.py      FlightLog: the one reader of a ULog file (topics, parameters, older topic names, missing-topic errors)
phases.py    armed, take-off, airborne, landing, found from the data
replay.py    PX4's mix rebuilt from the log's CA_* parameters; the IMU predicted through a platform
identify.py  thrust coefficient, hover command, mass, CoG offset, inertia ratios, motor time constant, and the
             base and arm inertial parameters of an aerial manipulator (Pinocchio's regressors), with uncertainties
synth.py     ULog files written from simulated flights (known truth for the tests and the docs)
show.py      the text summary of a log (qprr log show)
plots.py     the summary figure of a log
cli.py       FRONT END: qprr log show | replay | identify
"""
