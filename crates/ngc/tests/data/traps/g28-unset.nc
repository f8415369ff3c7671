(trap: G91 G28 Z0 on a machine that gives no reference position: refused, naming g28_mm)
G21 G90 G17
G0 X10 Y20 Z5
G91 G28 Z0
G90
M30
