(trap: Fanuc K is the canned cycle's repeat count: three holes 10 mm apart in G91)
G21 G90 G17
T1 M6
G0 X0 Y0 Z20
G91 G99 G81 X10 Z-12 R-18 K3 F100
G80 G90
M30
