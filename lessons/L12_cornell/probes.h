// L12's probes (lessons/L12_cornell/checks.py computes what they must return): the sampled
// bounce, Russian roulette, next-event estimation's connection to a point on an area light and
// its estimate, and the MIS weights of the path tracer (tracer/cpp/20_path.h).
#include "20_path.h"

RT_PROBE(sample_cosine) {
    double u1 = a.next();
    return rt::probe::out(rt::sample_cosine(u1, a.next()));
}

RT_PROBE(cosine_pdf) { return rt::probe::out(rt::cosine_pdf(a.next())); }

RT_PROBE(russian_roulette) {
    using rt::probe::out;
    rt::Color beta = a.color();
    bool goes_on = rt::russian_roulette(beta, a.next());
    return out(goes_on) + out(beta);
}

namespace l12 {

// A point on a light as sample_area_light() gives it: position, unit normal, density per area.
rt::LightPoint read_light_point(rt::probe::Args &a) {
    rt::LightPoint lp;
    lp.p = a.vec();
    lp.Ng = a.vec();
    lp.pdf_area = a.next();
    return lp;
}

} // namespace l12

RT_PROBE(connect_to_light) {
    using rt::probe::out;
    rt::Vec3 x = a.vec(), N = a.vec();
    rt::LightPoint lp = l12::read_light_point(a);
    rt::LightConnection c = rt::connect_to_light(x, N, lp, a.next());
    return out(c.wi) + out(c.cos_i) + out(c.cos_l) + out(c.pdf);
}

// The whole next-event estimate of one light point, unblocked: connect_to_light(), then
// light_estimate() with its cosine and density, as trace_path() does.
RT_PROBE(light_estimate) {
    rt::Vec3 x = a.vec(), N = a.vec();
    rt::LightPoint lp = l12::read_light_point(a);
    double pick = a.next();
    rt::Color beta = a.color(), f = a.color(), Le = a.color();
    double w = a.next();
    rt::LightConnection c = rt::connect_to_light(x, N, lp, pick);
    return rt::probe::out(rt::light_estimate(beta, f, Le, c.cos_i, w, c.pdf));
}

RT_PROBE(power_heuristic) {
    double f = a.next();
    return rt::probe::out(rt::power_heuristic(f, a.next()));
}

RT_PROBE(mis_weights) {
    using rt::probe::out;
    double pdf_light = a.next();
    rt::MISWeights w = rt::mis_weights(pdf_light, a.next());
    return out(w.light) + out(w.bsdf);
}
