(trap: G91 G28 Z0 with the reference Z450 machine: Z to 450, X Y stay)
G21 G90 G17
G0 X10 Y20 Z5
G91 G28 Z0
G90
M30
