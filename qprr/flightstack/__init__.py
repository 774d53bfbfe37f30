"""The flight stacks: a qprr platform carried to PX4 and ArduPilot, and their rotor geometry read back.

frames.py   qprr's body and world frames <-> PX4's FRD body and NED world frames (the one place they are converted)
px4.py      PX4's control allocation: CA_* rotor geometry, effectiveness matrix, normalised pseudo-inverse mix,
            .params files (QGroundControl), export from a platform at an arm pose, import to a qprr rotor file
ardupilot.py  ArduPilot: a Lua frame script (MotorsMatrix / Motors_6DoF) and the Motors_dynamic factor table
mixer.py    how wrong a fixed mixer becomes as the arm moves the centre of gravity (a design map)
cli.py      FRONT END: qprr export px4 | ardupilot, qprr import px4
"""
