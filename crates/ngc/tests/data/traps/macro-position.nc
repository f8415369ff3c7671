(trap: #5001 #5002 read the end point of the last block, work coordinates)
G21 G90 G17
G0 X12.5 Y-3 Z4
#100=#5001
#101=#5002
G0 X[#100+1] Y[#101*2]
M30
