"""GoalBook: what replaces the active goal, and a goal whose request is dropped (no DDS)."""

from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.action.goal_book import GoalBook, KIND, OWN_KINDS
from traj_gen_ros.node.action.goal_points import parse_trajectory_goal
from traj_gen_ros.node.action.tolerances import default_tolerances
from traj_gen_ros.node.requests.request import Request


def goal(request_id):
    points = parse_trajectory_goal(('a',), ['a'], [([0.5], (), (), 1.0)], 0)
    request = Request(KIND, {'request_id': str(request_id)}, 0, points)
    return ActiveGoal(None, points, request, default_tolerances(1, 0.0, 0.0, 0.0, 0.0))


def test_a_goals_own_request_makes_it_active_and_the_next_one_replaces_it():
    book = GoalBook()
    first = goal(1)
    book.starting = first
    book.accepted(first.request, 7)
    assert book.active is first and first.start_ns == 7 and book.replaced == []
    stop = Request('stop', {'request_id': '2'}, 0, None)
    book.accepted(stop, 9)
    assert book.active is None and book.replaced == [first]
    assert first.replaced == 'replaced by a ~/stop call (request_id 2); the arm brakes to rest'


def test_a_newer_goal_replaces_the_active_one_and_its_motion_continues():
    book = GoalBook()
    first, second = goal(1), goal(2)
    book.starting = first
    book.accepted(first.request, 7)
    book.starting = second
    book.accepted(second.request, 8)
    assert book.active is second and book.replaced == [first]
    assert first.replaced == ('replaced by a newer follow_joint_trajectory goal (request_id '
                              '2); its motion continues from the setpoint')


def test_the_actions_own_brake_replaces_nothing_and_a_cancel_notes_its_start():
    book = GoalBook()
    first = goal(1)
    book.starting = first
    book.accepted(first.request, 7)
    first.cancel = Request(OWN_KINDS[0], {}, 0, None)
    book.accepted(first.cancel, 11)
    book.accepted(Request(OWN_KINDS[1], {}, 0, None), 12)
    assert book.active is first and first.brake_start_ns == 11 and book.replaced == []


def test_a_goal_whose_request_is_dropped_before_its_start_is_aborted():
    book = GoalBook()
    first = goal(1)
    book.starting = first
    book.accepted(first.request, 7)
    book.dropped(Request('via_points', {}, 0, None), 'not this one')
    assert book.active is first
    book.dropped(first.request, 'the speed scaling factor changed')
    assert book.active is None and book.replaced == [first]
    assert first.replaced == 'dropped: the speed scaling factor changed'
