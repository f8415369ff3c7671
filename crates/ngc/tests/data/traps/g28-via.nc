(trap: G90 G28 X50 Z100: through the point X50 Z100, then X and Z to the reference, Y stays)
G21 G90 G17
G0 X10 Y20 Z5
G28 X50 Z100
M30
