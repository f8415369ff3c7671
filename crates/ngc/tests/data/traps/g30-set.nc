(trap: G91 G30 X0 Y0 with the G30 position X-100 Y200 machine: X Y there, Z stays)
G21 G90 G17
G0 X10 Y20 Z5
G91 G30 X0 Y0
G90
M30
