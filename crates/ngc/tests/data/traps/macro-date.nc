(trap: #3011, the date, is not modelled: refused, not read as 0)
G21 G90 G17
#100=#3011
G0 X#100
M30
