# Poste HTB/HTA, deux départs (thèse de Bergé, 1996, chapitre 5) : les textes de
# l'installation en français.

signal-c1 = Disjoncteur du départ D1 fermé
signal-def1 = Capteur intelligent de D1 : défaut préconfirmé (def+)
signal-def2_D1 = Image de l'état de défaut de D2 chez D1 (DefDep(D2) tel que le bus l'a livré)
signal-c2 = Disjoncteur du départ D2 fermé
signal-def2 = Capteur intelligent de D2 : défaut préconfirmé (def+)
signal-def1_D2 = Image de l'état de défaut de D1 chez D2 (DefDep(D1) tel que le bus l'a livré)
signal-pert1 = Environnement : perturbation sur la ligne D1 (posée par une panne du scénario ; lue par aucun programme)
signal-pert2 = Environnement : perturbation sur la ligne D2 (posée par une panne du scénario ; lue par aucun programme)
signal-ComOuv1 = Ouvrir le disjoncteur de D1
signal-ComFer1 = Fermer le disjoncteur de D1
signal-ComOuv2 = Ouvrir le disjoncteur de D2
signal-ComFer2 = Fermer le disjoncteur de D2

element-feeder-d1 = Départ D1
element-feeder-d2 = Départ D2
element-lines = Lignes

part-breaker1 = Disjoncteur D1
part-breaker2 = Disjoncteur D2
part-sensor1 = Capteur intelligent D1
part-sensor2 = Capteur intelligent D2
part-bus_d1 = Bus : DefDep(D1) vers D2
part-bus_d2 = Bus : DefDep(D2) vers D1
danger-double_fault = défaut double : courant de défaut dans les deux départs à la fois

constraint-CSf1 = pas de réenclenchement de D1 tant que D2 est connu en défaut : défaut double
constraint-CSf2 = pas de réenclenchement de D2 tant que D1 est connu en défaut : défaut double
constraint-CSf3 = disjoncteur de D1 commandé à l'ouverture et à la fermeture à la fois
constraint-CSf4 = disjoncteur de D2 commandé à l'ouverture et à la fermeture à la fois

off-ComOuv1 = pas d'ordre : le disjoncteur reste comme il est
off-ComFer1 = pas d'ordre : le disjoncteur reste comme il est
off-ComOuv2 = pas d'ordre : le disjoncteur reste comme il est
off-ComFer2 = pas d'ordre : le disjoncteur reste comme il est

scenario-reference = Poste : production (perturbations toutes les 3 s, bus à 50 ms)
scenario-case2-bus-50ms = Poste : cas 2, bus à 50 ms (pas de défaut double)
scenario-case1-bus-100ms = Poste : cas 1, bus à 100 ms (défaut double sur [580, 680) ms)
scenario-e01-reclose-onto-fault = Poste : E01, D2 réenclenche sur le défaut de D1

variant-E01 = Le réenclenchement rapide de D2 oublie l'autre départ (TO2 au lieu de TO2 . /def1_D2) : D2 réenclenche sur le défaut connu de D1, défaut double
variant-E02 = Le réenclenchement rapide de D1 oublie l'autre départ (TO1 au lieu de TO1 . /def2_D1)
variant-E03 = L'ouverture prolongée de D2 se termine sur le mauvais sens de l'image (def1_D2 au lieu de /def1_D2 + TW2) : D2 réenclenche dès qu'il sait D1 en défaut
