(trap: Haas #3026 reads the tool in the spindle)
G21 G90 G17
T3 M6
G0 X#3026 Y0 Z10
M30
