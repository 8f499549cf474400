# Alimentation en liquide à deux cuves (thèse d'Allahham, 2008, chapitre 6.4) : les
# textes de l'installation en français, lus par la console après les siens
# (`signal-<id>` : la description d'un signal). En anglais, la console montre les
# descriptions de plant.ron.

signal-h1 = Cuve 1 au niveau haut (pleine)
signal-b1 = Cuve 1 au niveau bas (vide)
signal-h2 = Cuve 2 au niveau haut (pleine)
signal-b2 = Cuve 2 au niveau bas (vide)
signal-C1 = Capteur de débit de la ligne de remplissage de la cuve 1 (en série avec M1 et V1) : le liquide circule
signal-C2 = Capteur de débit de la ligne de vidange de la cuve 1 (en série avec M2 et V2) : le liquide circule
signal-C3 = Capteur de débit de la ligne de remplissage de la cuve 2 (en série avec M3 et V3) : le liquide circule
signal-C4 = Capteur de débit de la ligne de vidange de la cuve 2 (en série avec M4 et V4) : le liquide circule
signal-d = Bouton d'ordre de départ (lance les deux remplissages)
signal-M1 = Pompe de remplissage de la cuve 1
signal-M2 = Pompe de vidange de la cuve 1
signal-M3 = Pompe de remplissage de la cuve 2
signal-M4 = Pompe de vidange de la cuve 2
signal-V1 = Vanne de remplissage de la cuve 1
signal-V2 = Vanne de vidange de la cuve 1
signal-V3 = Vanne de remplissage de la cuve 2
signal-V4 = Vanne de vidange de la cuve 2

# Les éléments de l'installation (`element` dans plant.ron : minuscules, espaces en
# tirets).
element-tank-1 = Cuve 1
element-tank-2 = Cuve 2
element-panel = Pupitre

# Ce que protège chaque contrainte (le commentaire de constraints.txt).
constraint-CSl1 = pas de remplissage de la cuve 1 au niveau haut : elle déborderait
constraint-CSl2 = pas de remplissage de la cuve 2 au niveau haut : elle déborderait
constraint-CSl3 = pas de vidange de la cuve 1 au niveau bas : sa pompe de vidange tournerait à sec
constraint-CSl4 = pas de vidange de la cuve 2 au niveau bas : sa pompe de vidange tournerait à sec
constraint-CSl5 = pompe de remplissage de la cuve 1 en marche contre sa vanne fermée
constraint-CSl6 = pompe de vidange de la cuve 1 en marche contre sa vanne fermée
constraint-CSl7 = pompe de remplissage de la cuve 2 en marche contre sa vanne fermée
constraint-CSl8 = pompe de vidange de la cuve 2 en marche contre sa vanne fermée

# Les sorties à l'arrêt (`off` dans plant.ron : ce que fait la machine quand la sortie
# est à 0).
off-M1 = la pompe s'arrête ; la cuve 1 garde son niveau
off-M2 = la pompe s'arrête ; la cuve 1 garde son niveau
off-M3 = la pompe s'arrête ; la cuve 2 garde son niveau
off-M4 = la pompe s'arrête ; la cuve 2 garde son niveau
off-V1 = la vanne ferme la ligne de remplissage de la cuve 1
off-V2 = la vanne ferme la ligne de vidange de la cuve 1
off-V3 = la vanne ferme la ligne de remplissage de la cuve 2
off-V4 = la vanne ferme la ligne de vidange de la cuve 2

# Les scénarios (`scenario-<nom du fichier>` : son titre dans la ligne d'état).
scenario-reference = Alimentation en liquide : deux cycles sans défaut
scenario-thesis-blocked-drain = Alimentation en liquide : vidange de la cuve 1 bouchée (thèse, chapitre 6.4)
scenario-e01-overflow = Alimentation en liquide : E01, cuve 1 remplie au-delà du niveau haut

# La bibliothèque d'erreurs de commande (programs/errors.ron).
variant-E01 = Remplissage de la cuve 1 arrêté sur le capteur de la cuve 2 (h2 au lieu de h1, recopié de l'autre branche) : M1 continue de pomper dans la cuve 1 pleine jusqu'à h2, 1 s plus tard
variant-E02 = Vanne de remplissage de la cuve 1 oubliée dans l'étape de remplissage (pas d'action V1 dans X11) : M1 pompe contre la vanne fermée
variant-E03 = Vidange de la cuve 2 arrêtée sur le capteur de la cuve 1 (b1 au lieu de b2, recopié de l'autre branche) : M4 continue de vider la cuve 2 sous son niveau bas
variant-E04 = Vidange de la cuve 1 arrêtée sur le capteur de la cuve 2 (b2 au lieu de b1) : la vidange de la cuve 1 s'arrête quand la cuve 2 est vide, avec environ 20 l dans la cuve 1, et le cycle suivant ne démarre jamais
variant-E05 = Remplissage de la cuve 2 arrêté sur le capteur de la cuve 1 (h1 au lieu de h2) : les deux remplissages s'arrêtent ensemble à 3,4 s, la cuve 2 aux trois quarts, et sa vidange part sans niveau haut

# Les tâches surveillées (tasks.ron) : le sujet de leurs alarmes.
task-fill1 = remplissage de la cuve 1 : M1 et V1 du niveau bas b1 au niveau haut h1
task-empty1 = vidange de la cuve 1 : M2 et V2 du niveau haut h1 au niveau bas b1
task-fill2 = remplissage de la cuve 2 : M3 et V3 du niveau bas b2 au niveau haut h2
task-empty2 = vidange de la cuve 2 : M4 et V4 du niveau haut h2 au niveau bas b2

# Les composants (components.ron).
part-tank1 = cuve 1
part-tank2 = cuve 2
part-start_button = bouton d'ordre de départ
