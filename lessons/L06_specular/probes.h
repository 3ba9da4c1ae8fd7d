// L06's probes (lessons/L06_specular/checks.py): the mirror vector and the Phong term.
#include "10_classic.h"

RT_PROBE(reflect) {
    rt::Vec3 d = a.vec();
    return rt::probe::out(rt::reflect(d, a.vec()));
}

RT_PROBE(phong_term) {
    rt::Vec3 R = a.vec(), L = a.vec();
    return rt::probe::out(rt::phong_term(R, L, a.next()));
}
