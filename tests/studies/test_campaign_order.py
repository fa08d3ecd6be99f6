"""The campaign's dispatch order: every job once; the pool's two first picks never share a scene
family (they would compile the same kernels twice on a fresh clone); within a family the
frequency cases lead."""
from compare.scenes import get_scene
from compare.workflows import campaign, campaign_plan


def test_dispatch_order_of_the_default_campaign():
    _, jobs = campaign_plan.plan_campaign(campaign_plan.load_campaign(None))
    order = campaign.dispatch_order(jobs)
    assert sorted(j.label for j in order) == sorted(j.label for j in jobs)
    family = [campaign._scene_module(get_scene(j.scene)) for j in order]
    n_families = len(set(family))
    # consecutive jobs differ in family until fewer families are left than the pool's width
    left = [len(set(family[i:])) for i in range(len(family))]
    assert all(a != b for a, b, n in zip(family, family[1:], left) if n > 2)
    for f in set(family):
        mine = [j for j, g in zip(order, family) if g == f]
        kinds = [j.solver is None for j in mine]
        assert kinds == sorted(kinds, reverse=True)          # frequency cases first
    assert n_families >= 4
