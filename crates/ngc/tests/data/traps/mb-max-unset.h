0 BEGIN PGM MBMAX MM
1 ; trap: M140 MB MAX (retract to the end of travel) with no reference position given
2 TOOL CALL 1 Z S1000
3 L X+10 Y+20 Z+5 R0 FMAX
4 L M140 MB MAX
5 END PGM MBMAX MM
