(trap: #3000 stops the program with its alarm text)
G21 G90 G17
G0 X1 Y1 Z10
#3000=7(SPINDLE NOT READY)
G0 X2
M30
