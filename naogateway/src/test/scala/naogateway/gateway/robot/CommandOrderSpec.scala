package naogateway.gateway.robot

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.gateway.robot.CommandOrder.{Entry, Refused, Step, Superseded, Transmit}
import naogateway.wire.ActuatorGroup

/** The command order's rules, over random scripts of calls and answers. */
class CommandOrderSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private sealed trait Op
  private final case class Submit(slot: Option[ActuatorGroup], safety: Boolean, replaceable: Boolean) extends Op
  private final case class Answer(pick: Int) extends Op

  private val ops: Gen[Op] = Gen.frequency(
    3 -> Gen.zip(Gen.option(Gen.oneOf(ActuatorGroup.slots)), Gen.frequency(1 -> true, 4 -> false),
      Gen.frequency(3 -> true, 1 -> false))
      .map((Submit.apply _).tupled),
    2 -> Gen.choose(0, 7).map(Answer.apply)
  )
  private val scripts = Gen.zip(Gen.choose(1, 4), Gen.choose(0, 4), Gen.listOf(ops))

  /** Runs a script, then answers everything in flight until nothing is left; returns every step with its order. */
  private def run(maxInFlight: Int, maxWaiting: Int, script: List[Op])
      : (Vector[(CommandOrder[Unit], Step[Unit])], Vector[Entry[Unit]], Vector[CommandOrder[Unit]]) = {
    var order = CommandOrder.empty[Unit](maxInFlight, maxWaiting)
    var steps = Vector.empty[(CommandOrder[Unit], Step[Unit])]
    var submitted = Vector.empty[Entry[Unit]]
    var states = Vector(order)
    def apply(r: (CommandOrder[Unit], Vector[Step[Unit]])): Unit = {
      order = r._1
      steps ++= r._2.map(order -> _)
      states :+= order
    }
    script.foreach {
      case Submit(slot, safety, replaceable) =>
        val e = Entry(submitted.size.toLong, slot, safety, (), replaceable)
        submitted :+= e
        apply(order.submit(e))
      case Answer(pick) =>
        if (order.inFlight.nonEmpty) apply(order.complete(order.inFlight(pick % order.inFlight.size).key))
    }
    while (order.inFlight.nonEmpty) apply(order.complete(order.inFlight.head.key))
    (steps, submitted, states)
  }

  private def sent(steps: Vector[(CommandOrder[Unit], Step[Unit])]): Vector[Entry[Unit]] =
    steps.collect { case (_, Transmit(e)) => e }

  "CommandOrder" should {
    "send a slot's calls in the order they were given: nothing older leaves after a newer one (no walk after a stop)" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, _, _) = run(max, waiting, script)
        ActuatorGroup.slots.foreach { slot =>
          val keys = sent(steps).filter(_.slot.contains(slot)).map(_.key)
          keys shouldBe keys.sorted.distinct
        }
      }
    }
    "end every call exactly once: sent, superseded or refused, and never send a superseded or refused one" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, submitted, _) = run(max, waiting, script)
        val ends = steps.map(_._2).collect {
          case Transmit(e)      => e.key -> "sent"
          case Refused(e)       => e.key -> "refused"
          case Superseded(e, _) => e.key -> "superseded"
        }
        // A sent call may be superseded while in flight; nothing else happens to a call twice.
        ends.groupBy(_._1).foreach { case (key, all) =>
          all.map(_._2) should (equal(Vector("sent")) or equal(Vector("refused")) or equal(Vector("superseded")) or
            equal(Vector("sent", "superseded")))
          withClue(s"call $key")(all.size should be <= 2)
        }
        ends.map(_._1).toSet shouldBe submitted.map(_.key).toSet
      }
    }
    "send a safety call at once, and keep other calls within the in-flight cap" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, submitted, states) = run(max, waiting, script)
        val sentKeys = sent(steps).map(_.key).toSet
        submitted.filter(_.safety).foreach(e => sentKeys should contain(e.key))
        states.foreach(s => s.inFlight.count(!_.safety) should be <= max)
        states.foreach(s => s.waiting.size should be <= waiting)
      }
    }
    "hold at most one live replaceable call per slot, and send other calls first come, first served" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, _, states) = run(max, waiting, script)
        states.foreach { s =>
          val live = (s.inFlight ++ s.waiting).filter(_.replaceable).flatMap(_.slot)
          live.distinct.size shouldBe live.size
        }
        val ordinary = sent(steps).filterNot(_.safety).map(_.key)
        ordinary shouldBe ordinary.sorted
      }
    }
    "let the latest call of each slot win: the last one sent is the last one given that was not refused" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, submitted, _) = run(max, waiting, script)
        val refused = steps.map(_._2).collect { case Refused(e) => e.key }.toSet
        ActuatorGroup.slots.foreach { slot =>
          val given = submitted.filter(e => e.slot.contains(slot) && !refused(e.key)).map(_.key)
          sent(steps).filter(_.slot.contains(slot)).map(_.key).lastOption shouldBe given.lastOption
        }
      }
    }
    "change nothing for a call it refuses: its slot's call in flight keeps going and a waiting stop still leaves" in {
      // The case the property above found (seed 1594188751653626614): one in flight, one waiting at most.
      val (steps, _, states) = run(
        1,
        1,
        List(
          Submit(None, safety = false, replaceable = true),
          Submit(Some(ActuatorGroup.Arms), safety = false, replaceable = true),
          Answer(0),
          Submit(Some(ActuatorGroup.Walk), safety = false, replaceable = false),
          Submit(Some(ActuatorGroup.Arms), safety = false, replaceable = true)
        )
      )
      steps.map(_._2).collect { case Refused(e) => e.key } shouldBe Vector(3L)
      steps.map(_._2).collect { case Superseded(e, _) => e.key } shouldBe empty
      sent(steps).map(_.key) shouldBe Vector(0L, 1L, 2L)
      states.last.waiting shouldBe empty
    }
    "never supersede a stop or a posture once sent: a newer call of the slot leaves after it and its caller keeps its answer" in {
      forAll(scripts) { case (max, waiting, script) =>
        val (steps, _, _) = run(max, waiting, script)
        steps.collect { case (_, Superseded(e, true)) => e }.foreach(_.replaceable shouldBe true)
      }
    }
    "withdraw nothing that is not in flight, and supersede a walk held behind the cap before a stop goes" in {
      val o0 = CommandOrder.empty[Unit](1, 4)
      val (o1, s1) = o0.submit(Entry(1, None, safety = false, ()))
      s1 shouldBe Vector(Transmit(Entry(1, None, safety = false, ())))
      val walk = Entry(2, Some(ActuatorGroup.Walk), safety = false, ())
      val (o2, s2) = o1.submit(walk)
      s2 shouldBe empty // waits behind the cap
      val stop = Entry(3, Some(ActuatorGroup.Walk), safety = true, ())
      val (o3, s3) = o2.submit(stop)
      s3 shouldBe Vector(Superseded(walk, wasInFlight = false), Transmit(stop))
      o3.waiting shouldBe empty
      o3.complete(1)._2 shouldBe empty
    }
  }
}
