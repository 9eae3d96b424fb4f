#pragma once
// General English vocabulary for the keyword-verification grammar: common function and content
// words (a general list, not tuned to any test material) plus words that sound like the
// keywords, so that a keyword wins only when it beats its acoustic competitors.
namespace sarmap {
namespace speech {

inline const char* kVerificationVocabulary =
    "a about above after again against all almost alone along already also always am among an and another any "
    "anyone anything are around as ask asked at away back bad be because been before behind being below best "
    "better between big black blue book both boy bring brought but by call called came can car care carry cat "
    "change child children city close cold come could country course cut day days dear did different do does dog "
    "done door down draw during each early earth east eat eight end enough even evening ever every eye eyes face "
    "fact fall family far fast father feel feet few fifty find fine fire first five floor follow food foot for "
    "form found four free friend friends from front full game gave get girl give go going gone good got great "
    "green ground group grow had half hand hands happen hard has have he head hear heard heart heavy held hello "
    "her high him himself his hold home hope horse hot hour house how however hundred i idea if important in "
    "inside into is it its just keep kind king knew know land large last late later learn leave left less let "
    "letter life light like line list little live long look looked lot love low made make man many may me mean "
    "men might mind minute miss money more morning most mother move much must my name near need never new next "
    "night nine no not nothing now number of off often oh old on once one only open or order other our out over "
    "own page paper part past people person picture place plan play please point power put question quick quite "
    "ran rather read ready real really red right river road room round run said same saw say school sea second "
    "see seem seen sell send sent seven several shall she short should show side since sing six size small so "
    "some something sometimes soon sound south speak stand start state still stop story street strong study such "
    "sun sure table take talk tell ten than thank that the their them then there these they thing things think "
    "third thirty this those though thought thousand three through time to today together told too took top "
    "toward town tree true try turn twenty two under until up upon us use used very voice wait walk want war "
    "warm was watch water way we week well went were west what when where which while white who whole why will "
    "wind window with without woman word words work world would write year years yes yet you young your "
    // Sound-alikes of the keywords (help, rescue, assist, here).
    "health hell helm helps helped self shelf elf yelp kelp whelp felt belt melt pelt else yell fell tell sell "
    "bell hair hear hero year ear near fear clear beer dear pier sheer cue rescued rest risky assistant sister "
    "insist resist exist list mist missed kissed desk this";

}  // namespace speech
}  // namespace sarmap
