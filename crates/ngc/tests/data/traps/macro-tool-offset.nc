(trap: #2001, a tool offset value, is not modelled: refused, not read as 0)
G21 G90 G17
G0 Z[#2001+10]
M30
