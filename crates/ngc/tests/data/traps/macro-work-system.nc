(trap: #4014 reads the work system, #4001 the last group-1 code)
G21 G90 G17
G55
G0 X0 Y0 Z10
G2 X0 Y0 I5 J0 F100
#100=#4014
#101=#4001
G54
G0 X#100 Y#101
M30
