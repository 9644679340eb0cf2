// Included by include_pair.comp, which it includes in turn.
#include "./include_pair.comp"
