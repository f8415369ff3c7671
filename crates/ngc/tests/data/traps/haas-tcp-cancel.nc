(trap: G234 with A90, then G49: the next block moves Z alone, from where the axes are)
G21 G90 G17
T1 M6
G43 H1
G0 X0 Y0 Z50 A0 C0
G234 H1
G1 X0 Y10 Z0 A90 C0 F500
G49
G1 Z20
M30
