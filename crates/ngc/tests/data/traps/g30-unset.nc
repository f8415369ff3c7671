(trap: G30 on a machine that gives no G30 position: refused, naming g30_mm)
G21 G90 G17
G0 X10 Y20 Z5
G91 G30 Z0
G90
M30
