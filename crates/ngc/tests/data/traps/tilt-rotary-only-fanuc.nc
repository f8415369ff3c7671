(trap: under G68.2 without TCP, a block of C alone turns C and moves no other axis)
G21 G90 G17
T1 M6
G43 H1
G0 X10 Y0 Z50
G68.2 X0 Y0 Z0 I0 J30 K0
G53.1
G0 X10 Y0 Z10
G0 C90
M30
