/* The scene rows, one line each, in the order mechpy lists them:
 * MP_MODEL(x) names the row `const mp_model mp_model_x` of a file under
 * csrc/models/ (models.c declares and tables them; no include guard: it is
 * read once per use). */
MP_MODEL(pendulum)
MP_MODEL(vanderpol)
MP_MODEL(duffing)
MP_MODEL(kepler)
MP_MODEL(r3b)
MP_MODEL(foucault)
MP_MODEL(rigid)
MP_MODEL(rigid_q)
MP_MODEL(heavy_top)
MP_MODEL(chain)
MP_MODEL(rocket)
