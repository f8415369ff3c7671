(trap: Haas mill G70 is a bolt hole circle, not a lathe cycle: its holes drilled by the active cycle)
G21 G90 G17
T1 M6
G0 X0 Y0 Z20
G81 Z-5 R2 F100 L0
G70 I20 J0 L4
G80
M30
